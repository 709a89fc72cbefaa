// Fusion of line depth maps into oriented points, on the analytic plane of
// strands (plane_scene_testing.h) with exact depths and directions that the
// stereo got wrong in a known way; and Luo Eq. 2's smoothing of directions.
#include "reconstruction/point_fusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "reconstruction/plane_scene_testing.h"
#include "reconstruction/point_orientation_field.h"

namespace hairrig {
namespace {

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return RadToDeg(std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0)));
}

double Median(std::vector<double> v) {
  if (v.empty()) return 1e9;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
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
  EXPECT_NEAR(stereo, 12.0, 0.5);
  // Tilting towards the cameras changes the projections least; the stereo's
  // direction, weighted a quarter of a view, keeps part of the tilt (4.7 deg).
  EXPECT_LT(multiview, 6.5);
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

TEST(PointFusion, BadOptionsAreRefused) {
  const PlaneScene scene = MakeScene();
  FusionOptions options;
  options.direction_sigma_mm = -1;
  EXPECT_EQ(FusePoints(scene.views, MapsWithTiltedDirections(scene, 0), options).status().code(),
            StatusCode::kInvalidArgument);
}

// Two layers of points 0.3 mm apart whose strands cross at 90 deg, each
// direction off by up to 15 deg at random.
std::vector<OrientedPoint> CrossingLayers(std::mt19937* rng) {
  std::uniform_real_distribution<double> noise(-DegToRad(15), DegToRad(15));
  std::vector<OrientedPoint> points;
  for (int layer = 0; layer < 2; ++layer) {
    for (int i = 0; i < 40; ++i) {
      for (int j = 0; j < 40; ++j) {
        OrientedPoint p;
        p.position_mm = Eigen::Vector3f(0.5f * static_cast<float>(i), 0.5f * static_cast<float>(j),
                                        0.3f * static_cast<float>(layer));
        const double a = (layer == 0 ? 0.0 : M_PI / 2) + noise(*rng), b = noise(*rng);
        p.direction =
            Eigen::Vector3d(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b))
                .cast<float>();
        p.confidence = 0.8f;
        points.push_back(p);
      }
    }
  }
  return points;
}

// Median and largest error against each layer's true direction.
std::pair<double, double> LayerErrors(const std::vector<OrientedPoint>& points) {
  std::vector<double> errors;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d truth =
        i < points.size() / 2 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    errors.push_back(AngleDeg(points[i].direction.cast<double>(), truth));
  }
  return {Median(errors), *std::max_element(errors.begin(), errors.end())};
}

TEST(PointOrientationField, SmoothingLowersNoiseAndKeepsCrossingLayersApart) {
  std::mt19937 rng(7);
  const std::vector<OrientedPoint> points = CrossingLayers(&rng);
  const auto [before, before_max] = LayerErrors(points);
  const auto [after, after_max] = LayerErrors(SmoothDirections(points, 1.5, 0.5, 2));
  std::printf("direction error median %.2f -> %.2f deg, largest %.1f -> %.1f deg\n", before, after,
              before_max, after_max);
  EXPECT_GT(before, 6.0);
  EXPECT_LT(after, before / 3);
  EXPECT_LT(after_max, 10.0);  // no point took the other layer's direction
}

}  // namespace
}  // namespace hairrig
