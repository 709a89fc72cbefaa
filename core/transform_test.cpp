#include "core/transform.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(Transform, ComposeAndInverseFollowTheNamingConvention) {
  const Rigid3d a_from_b = Rigid3d::FromAngleAxis({0.1, -0.2, 0.3}, {10, 20, 30});
  const Rigid3d b_from_c = Rigid3d::FromAngleAxis({-0.4, 0.1, 0.05}, {-5, 2, 7});
  const Eigen::Vector3d p_c(1, 2, 3);
  const Rigid3d a_from_c = a_from_b * b_from_c;
  EXPECT_LT((a_from_c * p_c - a_from_b * (b_from_c * p_c)).norm(), 1e-12);
  EXPECT_LT((a_from_c.Inverse() * (a_from_c * p_c) - p_c).norm(), 1e-12);
  EXPECT_NEAR(RotationDifferenceDeg(a_from_c, a_from_c), 0.0, 1e-9);
}

// The difference is measured at every size, down to 1e-12 rad, and is
// symmetric; the half turn and q = -q are handled.
TEST(Transform, RotationDifferenceIsExactFromTinyAnglesToAHalfTurn) {
  const Rigid3d a = Rigid3d::FromAngleAxis({0.3, -0.1, 0.2}, {0, 0, 0});
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -1).normalized();
  for (double angle_rad : {1e-12, 1e-9, 1e-6, 1e-3, 0.5, 2.0, kPi}) {
    const Rigid3d b = a * Rigid3d::FromAngleAxis(angle_rad * axis, {0, 0, 0});
    EXPECT_NEAR(RotationDifferenceDeg(a, b), RadToDeg(angle_rad),
                RadToDeg(1e-6 * angle_rad + 1e-14))
        << angle_rad;
    EXPECT_NEAR(RotationDifferenceDeg(b, a), RadToDeg(angle_rad),
                RadToDeg(1e-6 * angle_rad + 1e-14))
        << angle_rad;
  }
  Rigid3d negated = a;
  negated.rotation.coeffs() = -a.rotation.coeffs();
  EXPECT_EQ(RotationDifferenceDeg(a, negated), 0.0);
}

TEST(Transform, TurntableTurnsCounterClockwiseAboutUp) {
  const Eigen::Vector3d p = WorldFromTurntable(90.0) * Eigen::Vector3d(1, 0, 5);
  EXPECT_LT((p - Eigen::Vector3d(0, 1, 5)).norm(), 1e-12);
}

TEST(Transform, LookAtPutsTheTargetOnTheOpticalAxisWithUpUp) {
  const Eigen::Vector3d eye(1000, 0, 500), target(0, 0, 300);
  const Rigid3d cam_from_world = LookAt(eye, target);
  const Eigen::Vector3d t = cam_from_world * target;
  EXPECT_NEAR(t.x(), 0.0, 1e-9);
  EXPECT_NEAR(t.y(), 0.0, 1e-9);
  EXPECT_GT(t.z(), 0.0);
  // A point above the target appears higher in the image (smaller y).
  EXPECT_LT((cam_from_world * Eigen::Vector3d(0, 0, 400)).y(), 0.0);
  EXPECT_LT((cam_from_world * eye).norm(), 1e-9);
}

}  // namespace
}  // namespace hairrig
