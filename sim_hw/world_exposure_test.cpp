#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/core.hpp>

#include "core/truth_maps.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {
namespace {

std::shared_ptr<SimWorld> NoisyWorld() {
  auto scene = LoadScene("etc/scenes/default.yaml");
  EXPECT_TRUE(scene.ok()) << scene.status().ToString();
  scene->wig.num_strands = std::min(scene->wig.num_strands, 2000);
  SimWorldOptions options;
  options.time_scale = 0.01;
  options.noise = true;
  auto world = CreateSimWorld(*scene, options);
  EXPECT_TRUE(world.ok()) << world.status().ToString();
  for (const SceneLight& l : scene->lights)
    EXPECT_TRUE(SetWorldLightLevel(**world, l.name, 1.0).ok());
  return std::move(world).value();
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// A frame of an unchanged world is exposed again from the kept radiance: the
// same pixels as a fresh render for the same seed, its own noise for another.
TEST(WorldExposure, AnUnchangedWorldIsExposedAgainBitIdenticalToARender) {
  auto world = NoisyWorld();
  const WorldExposure exposure = ExposeWorldNow(*world);
  const cv::Mat first = RenderWorldExposure(*world, 0, exposure, 0.02, 0, 5).value();
  const cv::Mat again = RenderWorldExposure(*world, 0, exposure, 0.02, 0, 5).value();
  const cv::Mat other_seed = RenderWorldExposure(*world, 0, exposure, 0.02, 0, 6).value();
  EXPECT_TRUE(Identical(first, again));
  EXPECT_FALSE(Identical(first, other_seed));

  int recorded = 0;  // with a recorder installed every frame is rendered with its maps
  SetWorldTruthRecorder(*world, [&](int, double, const ViewTruthMaps&) { ++recorded; });
  const cv::Mat rendered = RenderWorldExposure(*world, 0, exposure, 0.02, 0, 5).value();
  SetWorldTruthRecorder(*world, nullptr);
  EXPECT_EQ(recorded, 1);
  EXPECT_TRUE(Identical(first, rendered));
}

TEST(WorldExposure, AChangedLightOrAngleRendersAgain) {
  auto world = NoisyWorld();
  WorldExposure exposure = ExposeWorldNow(*world);
  const cv::Mat lit = RenderWorldExposure(*world, 0, exposure, 0.02, 0, 5).value();
  WorldExposure dark = exposure;
  std::fill(dark.light_levels.begin(), dark.light_levels.end(), 0.0);
  const cv::Mat unlit = RenderWorldExposure(*world, 0, dark, 0.02, 0, 5).value();
  EXPECT_LT(cv::mean(unlit)[1] * 4, cv::mean(lit)[1]);
  WorldExposure turned = exposure;
  turned.angle_deg += 30;
  const cv::Mat turned_image = RenderWorldExposure(*world, 0, turned, 0.02, 0, 5).value();
  EXPECT_GT(cv::norm(turned_image, lit, cv::NORM_L1) / static_cast<double>(lit.total()), 1.0);
}

}  // namespace
}  // namespace hairrig
