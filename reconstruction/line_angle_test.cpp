#include "reconstruction/line_angle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hairrig {
namespace {

double ExactLineAngleDeg(double dx, double dy) {
  double a = std::atan2(dy, dx) * 180.0 / M_PI;
  if (a < 0) a += 180;
  return a >= 180 ? 0 : a;
}

TEST(LineAngle, AgreesWithAtan2Within0_00075Degrees) {
  double worst = 0;
  for (int k = 0; k < 36000; ++k) {
    const double a = k * 0.01 * M_PI / 180.0;
    for (double length : {0.3, 1.0, 250.0}) {
      const double dx = length * std::cos(a), dy = length * std::sin(a);
      const double diff = LineAngleDifferenceDeg(LineAngleDeg(dx, dy), ExactLineAngleDeg(dx, dy));
      worst = std::max(worst, diff);
    }
  }
  EXPECT_LT(worst, 0.00075);
}

TEST(LineAngle, AxesAndDirectionsOfTheSameLine) {
  EXPECT_DOUBLE_EQ(LineAngleDeg(1, 0), 0);
  EXPECT_DOUBLE_EQ(LineAngleDeg(-1, 0), 0);
  EXPECT_NEAR(LineAngleDeg(0, 1), 90, 1e-9);
  EXPECT_NEAR(LineAngleDeg(0, -1), 90, 1e-9);
  EXPECT_NEAR(LineAngleDeg(1, 1), LineAngleDeg(-1, -1), 1e-12);
  EXPECT_NEAR(LineAngleDeg(-1, 1), 135, 0.001);
  EXPECT_DOUBLE_EQ(LineAngleDeg(0, 0), 0);
}

TEST(LineAngle, DifferenceIsTheSmallerWayRound) {
  EXPECT_DOUBLE_EQ(LineAngleDifferenceDeg(10, 170), 20);
  EXPECT_DOUBLE_EQ(LineAngleDifferenceDeg(170, 10), 20);
  EXPECT_DOUBLE_EQ(LineAngleDifferenceDeg(0, 90), 90);
  EXPECT_DOUBLE_EQ(LineAngleDifferenceDeg(45, 50), 5);
}

}  // namespace
}  // namespace hairrig
