// Test helper: etc/scenes/default.yaml loaded, a failed load reported as a
// test failure naming the file and field. Run from the repository root (as
// ctest does).
#pragma once

#include <gtest/gtest.h>

#include "sim_hw/scene.h"

namespace hairrig_test {

inline hairrig::Scene DefaultScene() {
  auto scene = hairrig::LoadScene("etc/scenes/default.yaml");
  EXPECT_TRUE(scene.ok()) << scene.status().ToString();
  return scene.ok() ? *scene : hairrig::Scene{};
}

}  // namespace hairrig_test
