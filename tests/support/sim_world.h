// Test helper: the simulated world of etc/scenes/default.yaml (or another
// scene), noise-free and 100x faster than real time, optionally with its
// panels on. The wig is thinned to kDriverTestStrands: these tests check
// device protocols and timing, not the hair in the frames, and a frame of the
// full wig costs several times more to render. Header-only; run from the
// repository root (as ctest does).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "sim_hw/scene.h"
#include "sim_hw/sim_devices.h"

namespace hairrig_test {

inline std::shared_ptr<hairrig::SimWorld> MakeSimWorld(
    std::vector<hairrig::SimFault> faults = {}, bool lights_on = false,
    const std::string& scene_path = "etc/scenes/default.yaml") {
  auto scene = hairrig::LoadScene(scene_path);
  EXPECT_TRUE(scene.ok()) << scene.status().ToString();
  constexpr int kDriverTestStrands = 3000;
  scene->wig.num_strands = std::min(scene->wig.num_strands, kDriverTestStrands);
  hairrig::SimWorldOptions options;
  options.time_scale = 0.01;
  options.noise = false;
  options.faults = std::move(faults);
  auto world = hairrig::CreateSimWorld(*scene, options);
  EXPECT_TRUE(world.ok()) << world.status().ToString();
  if (lights_on) {
    for (const hairrig::SceneLight& l : scene->lights) {
      EXPECT_TRUE(hairrig::SetWorldLightLevel(**world, l.name, 1.0).ok());
    }
  }
  return std::move(world).value();
}

}  // namespace hairrig_test
