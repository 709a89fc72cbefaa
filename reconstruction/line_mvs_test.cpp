// Line MVS on an analytic scene (tests/support/plane_scene_testing.h): the orientation maps
// and grey images are exact projections, so the depth found must be the plane's.
#include "reconstruction/line_mvs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/support/plane_scene_testing.h"

namespace hairrig {
namespace {

using namespace plane_scene;

// Median absolute depth error over the estimated cells of view `v`, and the share estimated.
std::pair<double, double> DepthError(const PlaneScene& scene, const LineDepthMap& map, int v) {
  std::vector<double> errors;
  int hair = 0;
  for (int gy = 0; gy < map.depth_mm.rows; ++gy) {
    for (int gx = 0; gx < map.depth_mm.cols; ++gx) {
      const int x = gx * map.stride_px, y = gy * map.stride_px;
      if (!scene.views[static_cast<size_t>(v)].hair(y, x)) continue;
      ++hair;
      if (map.depth_mm(gy, gx) <= 0) continue;
      errors.push_back(
          std::abs(map.depth_mm(gy, gx) - scene.true_depth[static_cast<size_t>(v)](y, x)));
    }
  }
  if (errors.empty()) return {1e9, 0};
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2),
                   errors.end());
  return {errors[errors.size() / 2], static_cast<double>(errors.size()) / std::max(1, hair)};
}

// Measures one cost on view 1 and the neighbours of every view; returns the median depth error.
double MedianDepthError(const PlaneScene& scene, MvsCost cost, bool follow_orientation = true) {
  LineMvsOptions options;
  options.cost = cost;
  options.follow_orientation = follow_orientation;
  options.stride_px = 2;
  options.iterations = 6;  // no prior depth: the search spans +-depth_margin_mm
  options.neighbours = 3;
  options.views_in_cost = 3;
  options.max_baseline_deg = 60;
  options.depth_margin_mm = 150;
  auto maps = ComputeLineDepthMaps(scene.views, options);
  EXPECT_TRUE(maps.ok()) << maps.status().ToString();
  if (!maps.ok()) return 1e9;
  const auto [median, share] = DepthError(scene, (*maps)[1], 1);
  EXPECT_GT(share, 0.95);
  return median;
}

TEST(LineMvs, FindsThePlaneWithOrientationAndPhotometry) {
  const double median = MedianDepthError(MakeScene(), MvsCost::kBoth);
  std::printf("orientation + photometric cost: median depth error %.2f mm\n", median);
  EXPECT_LT(median, 1.2);  // 0.37 mm measured
}

// A segment's direction can tilt to match one neighbour's orientation at any
// depth; depth comes only from how the orientation field changes across the
// views, which on this slowly turning field is weak (the bound allows 30 mm
// of hypotheses drawn over +-150 mm; 1.0 mm measured).
TEST(LineMvs, OrientationAloneNarrowsTheDepth) {
  const double median = MedianDepthError(MakeScene(), MvsCost::kOrientation);
  std::printf("orientation cost alone: median depth error %.2f mm\n", median);
  EXPECT_LT(median, 30.0);
}

// On wavy strands a straight segment leaves the strand within its own
// length, so at the true depth its ends disagree with the neighbours' maps; the
// samples along the reference map's streamline stay on it.
TEST(LineMvs, SamplesAlongTheStreamlineFollowWavyStrands) {
  const PlaneScene scene = MakeScene(WavyStrandAngle);
  const double along = MedianDepthError(scene, MvsCost::kOrientation, true);
  const double straight = MedianDepthError(scene, MvsCost::kOrientation, false);
  std::printf(
      "wavy strands, orientation cost: median depth error %.2f mm along the streamline, "
      "%.2f mm straight\n",
      along, straight);
  EXPECT_LT(along, 0.5 * straight);
}

TEST(LineMvs, FindsThePlaneFromPhotometryAlone) {
  const PlaneScene scene = MakeScene();
  LineMvsOptions options;
  options.cost = MvsCost::kPhotometric;
  options.neighbours = 2;
  options.stride_px = 2;
  options.iterations = 6;
  options.depth_margin_mm = 150;
  auto maps = ComputeLineDepthMaps(scene.views, options);
  ASSERT_TRUE(maps.ok()) << maps.status().ToString();
  const auto [median, share] = DepthError(scene, (*maps)[1], 1);
  std::printf("view 1: photometric cost, median depth error %.2f mm\n", median);
  EXPECT_LT(median, 2.0);
}

TEST(LineMvs, NeighboursAreTheClosestViewsWithinTheBaselines) {
  const PlaneScene scene = MakeScene();
  LineMvsOptions options;
  options.neighbours = 2;
  EXPECT_EQ(NeighbourViews(scene.views, 1, options), (std::vector<int>{0, 2}));
  options.min_baseline_deg = 25;
  EXPECT_EQ(NeighbourViews(scene.views, 1, options), (std::vector<int>{3}));
}

TEST(LineMvs, BadInputIsRefused) {
  PlaneScene scene = MakeScene();
  LineMvsOptions options;
  options.samples = 4;
  EXPECT_EQ(ComputeLineDepthMaps(scene.views, options).status().code(),
            StatusCode::kInvalidArgument);
  options = LineMvsOptions();
  EXPECT_EQ(ComputeLineDepthMaps({scene.views[0]}, options).status().code(),
            StatusCode::kInvalidArgument);
  scene.views[2].hair = cv::Mat1b(10, 10, uint8_t{0});
  EXPECT_EQ(ComputeLineDepthMaps(scene.views, options).status().code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
