#include "sim_hw/head_model.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(HairRender, Placeholder) {}

}  // namespace
}  // namespace hairrig
