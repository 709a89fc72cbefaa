#include "reconstruction/mls.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hairrig {
namespace {

// Points on the plane z = 0.1 x, spread 0.5 mm along its normal, directions
// tilted out of it by the same noise.
std::vector<OrientedPoint> NoisyPlane(int n, double noise_mm, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> along(-20.f, 20.f);
  std::normal_distribution<float> across(0.f, static_cast<float>(noise_mm));
  const Eigen::Vector3f normal = Eigen::Vector3f(-0.1f, 0.f, 1.f).normalized();
  std::vector<OrientedPoint> points(static_cast<size_t>(n));
  for (OrientedPoint& p : points) {
    const float x = along(rng), y = along(rng);
    p.position_mm = Eigen::Vector3f(x, y, 0.1f * x) + across(rng) * normal;
    p.direction =
        (Eigen::Vector3f(1.f, 0.f, 0.1f).normalized() + 0.2f * across(rng) * normal).normalized();
  }
  return points;
}

double RmsOffPlane(const std::vector<OrientedPoint>& points) {
  const Eigen::Vector3f normal = Eigen::Vector3f(-0.1f, 0.f, 1.f).normalized();
  double sum = 0;
  for (const OrientedPoint& p : points) sum += std::pow(p.position_mm.dot(normal), 2);
  return std::sqrt(sum / static_cast<double>(points.size()));
}

TEST(Mls, SmoothingPullsNoisyPointsOntoTheirSurface) {
  const std::vector<OrientedPoint> noisy = NoisyPlane(20000, 0.5, 3);
  const std::vector<OrientedPoint> smooth = SmoothByMls(noisy, 2.0, 2);
  ASSERT_EQ(smooth.size(), noisy.size());
  const double before = RmsOffPlane(noisy), after = RmsOffPlane(smooth);
  std::printf("RMS off the plane: %.3f mm before, %.3f mm after\n", before, after);
  EXPECT_NEAR(before, 0.5, 0.02);
  EXPECT_LT(after, 0.25 * before);
  const Eigen::Vector3f normal = Eigen::Vector3f(-0.1f, 0.f, 1.f).normalized();
  double tilt = 0;
  for (const OrientedPoint& p : smooth) tilt += std::abs(p.direction.dot(normal));
  EXPECT_LT(tilt / static_cast<double>(smooth.size()), 0.02) << "directions lie in the plane";
}

TEST(Mls, APointWithoutNeighboursStaysWhereItIs) {
  std::vector<OrientedPoint> points = NoisyPlane(2000, 0.1, 4);
  OrientedPoint alone;
  alone.position_mm = Eigen::Vector3f(500, 500, 500);
  alone.direction = Eigen::Vector3f::UnitZ();
  points.push_back(alone);
  const std::vector<OrientedPoint> smooth = SmoothByMls(points, 2.0, 1);
  EXPECT_EQ(smooth.back().position_mm, alone.position_mm);
  EXPECT_EQ(smooth.back().direction, alone.direction);
  std::vector<Eigen::Vector3f> positions;
  for (const OrientedPoint& p : points) positions.push_back(p.position_mm);
  const PointSetSurface surface(positions, 2.0);
  Eigen::Vector3f projected, normal;
  EXPECT_FALSE(surface.Project(alone.position_mm, &projected, &normal));
  ASSERT_TRUE(surface.Project(Eigen::Vector3f(0, 0, 3), &projected, &normal));
  EXPECT_NEAR(std::abs(normal.z()), 0.995, 0.01);
  EXPECT_NEAR(projected.z(), 0.0, 0.1);
}

}  // namespace
}  // namespace hairrig
