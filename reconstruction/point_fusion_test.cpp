// Fusion of line depth maps into oriented points, on the analytic plane of
// strands (tests/support/plane_scene_testing.h) with exact depths and directions that the
// stereo got wrong in a known way.
#include "reconstruction/point_fusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <vector>

#include "core/statistics.h"
#include "tests/support/plane_scene_testing.h"

namespace hairrig {
namespace {

using namespace plane_scene;

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return RadToDeg(std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0)));
}

// Every view's map holds the plane's true depth and the true strand direction
// turned `tilt_deg` out of the plane, towards its normal: an error every view
// agrees on, as when the stereo's tilt is off.
std::vector<LineDepthMap> MapsWithTiltedDirections(const PlaneScene& scene, double tilt_deg) {
  std::vector<LineDepthMap> maps;
  const double tilt = DegToRad(tilt_deg);
  for (size_t v = 0; v < scene.views.size(); ++v) {
    const MvsView& view = scene.views[v];
    LineDepthMap map;
    map.stride_px = 2;
    const int rows = kSceneHeight / 2, cols = kSceneWidth / 2;
    map.depth_mm = cv::Mat1f(rows, cols, 0.f);
    map.cost = cv::Mat1f(rows, cols, 1.f);
    map.direction = cv::Mat3f(rows, cols, cv::Vec3f(0, 0, 0));
    const Rigid3d object_from_cam = view.cam_from_object.Inverse();
    for (int gy = 0; gy < rows; ++gy) {
      for (int gx = 0; gx < cols; ++gx) {
        const float depth = scene.true_depth[v](gy * 2, gx * 2);
        if (!(depth > 0)) continue;
        const Eigen::Vector2d n = *UndistortPixel(view.camera, Eigen::Vector2d(gx * 2, gy * 2));
        const Eigen::Vector3d p = object_from_cam * (Eigen::Vector3d(n.x(), n.y(), 1) * depth);
        const Eigen::Vector3d t =
            std::cos(tilt) * StrandDirection(p) + std::sin(tilt) * Eigen::Vector3d::UnitZ();
        map.depth_mm(gy, gx) = depth;
        map.cost(gy, gx) = 0.1f;
        map.direction(gy, gx) = cv::Vec3f(static_cast<float>(t.x()), static_cast<float>(t.y()),
                                          static_cast<float>(t.z()));
      }
    }
    maps.push_back(map);
  }
  return maps;
}

// Median angle (deg) between the fused points' directions and the plane's.
double MedianDirectionError(const PlaneScene& scene, const FusionOptions& options) {
  const auto points = FusePoints(scene.views, MapsWithTiltedDirections(scene, 12), options);
  EXPECT_TRUE(points.ok()) << points.status().ToString();
  if (!points.ok()) return 1e9;
  EXPECT_GT(points->size(), 5000u);
  std::vector<double> errors;
  for (const OrientedPoint& p : *points)
    errors.push_back(
        AngleDeg(p.direction.cast<double>(), StrandDirection(p.position_mm.cast<double>())));
  return Median(errors);
}

TEST(PointFusion, DirectionsFromEveryViewsOrientationCorrectTheStereosTilt) {
  const PlaneScene scene = MakeScene();
  FusionOptions options;
  options.direction_sigma_mm = 0;
  options.multiview_direction = false;
  const double stereo = MedianDirectionError(scene, options);
  options.multiview_direction = true;
  const double multiview = MedianDirectionError(scene, options);
  std::printf("median direction error: stereo's %.2f deg, from the views' orientation %.2f deg\n",
              stereo, multiview);
  EXPECT_NEAR(stereo, 12.0, 0.01);
  // Tilting towards the cameras changes the projections least; the stereo's
  // direction, weighted a quarter of a view, keeps part of the tilt.
  EXPECT_NEAR(multiview, 4.7, 1.0);
}

// The maps' cost is 0.1 everywhere, so a point's confidence comes from the
// views that agree with it: 0.45 for one besides the reference, 0.79 for three.
TEST(PointFusion, ConfidenceGrowsWithTheViewsThatAgree) {
  const PlaneScene scene = MakeScene();
  FusionOptions options;
  const auto points = FusePoints(scene.views, MapsWithTiltedDirections(scene, 0), options);
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  std::vector<double> by_agreeing(4, -1);
  for (const OrientedPoint& p : *points) {
    ASSERT_GE(p.views.size(), 2u);
    const size_t agreeing = std::min<size_t>(p.views.size() - 1, 3);
    by_agreeing[agreeing] = std::max(by_agreeing[agreeing], static_cast<double>(p.confidence));
  }
  EXPECT_NEAR(by_agreeing[1], 0.9 * 0.5, 1e-4);
  EXPECT_NEAR(by_agreeing[3], 0.9 * 0.875, 1e-4);
}

// Two views of the plane: the first's map holds every cell, the second's
// depths on every other row and column of its grid only, as a thin wisp's
// map does where the grid falls beside it, each off by `offset_mm`.
struct SparsePair {
  std::vector<MvsView> views;
  std::vector<LineDepthMap> maps;
};
SparsePair SparseSecondView(const PlaneScene& scene, double offset_mm) {
  SparsePair pair;
  std::vector<LineDepthMap> maps = MapsWithTiltedDirections(scene, 0);
  pair.views = {scene.views[0], scene.views[1]};
  pair.maps = {maps[0], maps[1]};
  LineDepthMap& sparse = pair.maps[1];
  for (int gy = 0; gy < sparse.depth_mm.rows; ++gy)
    for (int gx = 0; gx < sparse.depth_mm.cols; ++gx) {
      if (gy % 2 != 0 || gx % 2 != 0) {
        sparse.depth_mm(gy, gx) = 0;
        sparse.cost(gy, gx) = 1;
      } else {
        sparse.depth_mm(gy, gx) += static_cast<float>(offset_mm);
      }
    }
  return pair;
}

// The first view's cells whose projections fall on an empty cell of the
// other view's map find the agreeing cell beside it within
// agreement_radius_cells; depths that disagree confirm nothing there either.
TEST(PointFusion, ThinStructuresAgreeThroughTheCellsBesideTheirProjection) {
  const PlaneScene scene = MakeScene();
  FusionOptions options;
  options.direction_sigma_mm = 0;
  const auto count = [&](int radius, double offset_mm) {
    options.agreement_radius_cells = radius;
    const SparsePair pair = SparseSecondView(scene, offset_mm);
    const auto points = FusePoints(pair.views, pair.maps, options);
    EXPECT_TRUE(points.ok()) << points.status().ToString();
    return points.ok() ? points->size() : size_t{0};
  };
  const size_t nearest = count(0, 0), beside = count(1, 0);
  std::printf("points: %zu from the nearest cell, %zu with the cells beside it\n", nearest, beside);
  EXPECT_GT(static_cast<double>(beside), 1.5 * static_cast<double>(nearest));
  EXPECT_EQ(count(1, 5.0), 0u);
}

TEST(PointFusion, BadOptionsAreRefused) {
  FusionOptions options;
  options.direction_sigma_mm = -1;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
  options.direction_sigma_mm = 51;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
  options.direction_sigma_mm = 0;
  EXPECT_TRUE(options.Check().ok());
  options.agreement_radius_cells = -1;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
  options.agreement_radius_cells = 4;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
