#include "sim_hw/head_model.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(HeadModel, Placeholder) {}

}  // namespace
}  // namespace hairrig
