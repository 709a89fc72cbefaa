// Luo 2013 Sec. 4 Eq. 2's orientation field used to smooth the directions of
// a point cloud: random direction noise falls and crossing layers stay apart.
#include "reconstruction/point_orientation_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "core/statistics.h"
#include "core/transform.h"

namespace hairrig {
namespace {

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return RadToDeg(std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0)));
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
        const double a = (layer == 0 ? 0.0 : DegToRad(90)) + noise(*rng), b = noise(*rng);
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
