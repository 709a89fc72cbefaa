#include "reconstruction/circle_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace hairrig {
namespace {

// Points on the circle (centre, normal, radius) from angle `from` to `to`
// (rad), `count` of them, with Gaussian noise of `noise_mm` per coordinate.
std::vector<Eigen::Vector3d> Arc(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal,
                                 double radius, double from, double to, int count, double noise_mm,
                                 uint32_t seed) {
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_mm);
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < count; ++k) {
    const double a = from + (to - from) * k / (count - 1);
    points.push_back(centre + radius * (std::cos(a) * u + std::sin(a) * v) +
                     Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  return points;
}

TEST(CircleFit, RecoversRadiusCentreAndPlaneFromANoisyArc) {
  const Eigen::Vector3d centre(10, -5, 30), normal = Eigen::Vector3d(1, 2, 3).normalized();
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const auto points = Arc(centre, normal, 40.0, 0.3, 0.3 + M_PI / 2, 20, 0.1, seed);
    Circle3 fit;
    const double rms = FitCircle3(points, &fit);
    EXPECT_LT(rms, 0.25) << "seed " << seed;
    EXPECT_NEAR(fit.radius, 40.0, 0.8) << "seed " << seed;  // 2 %
    EXPECT_LT((fit.center - centre).norm(), 1.0) << "seed " << seed;
    EXPECT_GT(std::abs(fit.normal.dot(normal)), 0.995) << "seed " << seed;
  }
}

TEST(CircleFit, TaubinFindsTheRadiusOfANearlyStraightArc) {
  // A 60 mm chord of a 5 m circle: the arc departs from its chord by 0.09 mm.
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < 31; ++k) {
    const double a = -0.006 + 0.012 * k / 30;
    points.emplace_back(5000 * std::sin(a), 5000 * std::cos(a) - 5000);
  }
  Eigen::Vector2d centre;
  double radius = 0;
  ASSERT_TRUE(FitCircleTaubin(points, &centre, &radius));
  EXPECT_NEAR(radius, 5000, 50);
  EXPECT_NEAR(centre.y(), -5000, 50);
  Circle3 fit;
  std::vector<Eigen::Vector3d> points3;
  for (const Eigen::Vector2d& p : points) points3.emplace_back(p.x(), 7.0, p.y());
  EXPECT_LT(FitCircle3(points3, &fit), 1e-3);
  EXPECT_NEAR(fit.radius, 5000, 50);
}

TEST(CircleFit, CollinearPointsGiveTheLargestRadiusNotNaN) {
  std::vector<Eigen::Vector3d> line;
  for (int k = 0; k < 10; ++k) line.emplace_back(1.0 + 2 * k, 2.0 - k, 3.0);
  Circle3 fit;
  const double rms = FitCircle3(line, &fit);
  EXPECT_LT(rms, 1e-3);
  EXPECT_GT(fit.radius, 0.99 * kMaxCircleRadiusMm);
  EXPECT_TRUE(fit.center.allFinite());
  EXPECT_LT(fit.Curvature(), 1e-5);
  // Fewer than 3 points, or all in one place: no fit.
  EXPECT_FALSE(std::isfinite(FitCircle3({line[0], line[1]}, &fit)));
  EXPECT_FALSE(std::isfinite(FitCircle3({line[0], line[0], line[0]}, &fit)));
}

TEST(CircleFit, SweepOverlapTellsAnArcFromOneThatDoublesBack) {
  const Eigen::Vector3d centre(0, 0, 0), normal(0, 0, 1);
  const auto forward = Arc(centre, normal, 20.0, 0.0, 2.0, 15, 0.0, 1);
  Circle3 circle;
  circle.center = centre;
  circle.radius = 20;
  circle.normal = -normal;
  OrientByTraversal(forward, &circle);
  EXPECT_GT(circle.normal.z(), 0.99);  // counter-clockwise about +z
  EXPECT_NEAR(SweepOverlap(forward, circle), 0.0, 1e-9);
  auto back_and_forth = forward;
  back_and_forth.insert(back_and_forth.end(), forward.rbegin(), forward.rend());
  EXPECT_GT(SweepOverlap(back_and_forth, circle), 0.9);
}

}  // namespace
}  // namespace hairrig
