#include "reconstruction/helix_continuation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hairrig {
namespace {

// The unit tangent of a helix about +z at arc length s (mm): radius r, rise c per radian,
// handedness +1 (right-handed) or -1.
Eigen::Vector3f HelixTangent(double s, double r, double c, double handedness) {
  const double l = std::sqrt(r * r + c * c), t = s / l;
  return Eigen::Vector3d(-r * std::sin(t), handedness * r * std::cos(t), c)
      .normalized()
      .cast<float>();
}

double AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::clamp(static_cast<double>(a.normalized().dot(b.normalized())), -1.0, 1.0)) *
         180 / M_PI;
}

// Followed along a curl for the window, then carried on about the true axis:
// the tangents stay on the curl for a whole turn, whichever its handedness.
TEST(HelixContinuation, CarriesACurlOnForAWholeTurn) {
  for (const double handedness : {1.0, -1.0}) {
    const double r = 5, c = 3;  // a ringlet: radius 5 mm, pitch 19 mm, 59 deg off its axis
    const double step = 1.0;
    HelixContinuation helix({}, step);
    double s = 0;
    for (; s < 20; s += step) helix.Follow(HelixTangent(s, r, c, handedness));
    Eigen::Vector3f previous = HelixTangent(s - step, r, c, handedness), next;
    double worst = 0;
    const double turn = 2 * M_PI * std::sqrt(r * r + c * c);
    for (double t = s; t < s + turn; t += step) {
      ASSERT_TRUE(helix.Continue(previous, Eigen::Vector3f::UnitZ(), &next));
      worst = std::max(worst, AngleDeg(next, HelixTangent(t, r, c, handedness)));
      previous = next;
    }
    EXPECT_LT(worst, 10.0) << "handedness " << handedness;
    // Along the axis alone (the field) the strand is the helix angle off everywhere.
    EXPECT_GT(AngleDeg(Eigen::Vector3f::UnitZ(), HelixTangent(s, r, c, handedness)), 50.0);
  }
}

// The bend of the last tangents followed: at their middle, the helix's own
// tangent and its principal normal, which lies square to the axis, towards it.
// A straight stretch has none.
TEST(HelixContinuation, TheBendFollowedPointsAtTheCurlsAxis) {
  const double r = 5, c = 3, step = 1.0;
  HelixContinuation helix({}, step);
  Eigen::Vector3f tangent = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::Zero();
  EXPECT_FALSE(helix.Bend(4, 0.1, &tangent, &normal));
  double s = 0;
  for (; s < 10; s += step) helix.Follow(HelixTangent(s, r, c, 1));
  ASSERT_TRUE(helix.Bend(4, 0.1, &tangent, &normal));
  // Midway between the last tangent (s - step) and the one 4 steps before
  // (the mean of two tangents leans a little towards the axis); the helix
  // about +z has its axis at -(cos t, sin t) from its point.
  const double middle = s - 3 * step, t = middle / std::sqrt(r * r + c * c);
  EXPECT_LT(AngleDeg(tangent, HelixTangent(middle, r, c, 1)), 3.0);
  EXPECT_LT(AngleDeg(normal, Eigen::Vector3d(-std::cos(t), -std::sin(t), 0).cast<float>()), 1.0);
  HelixContinuation straight({}, step);
  for (int k = 0; k < 10; ++k) straight.Follow(Eigen::Vector3f(0, 0, -1));
  EXPECT_FALSE(straight.Bend(4, 0.1, &tangent, &normal));
}

TEST(HelixContinuation, LeavesAStraightStrandToTheField) {
  HelixContinuation helix({}, 1.0);
  Eigen::Vector3f next = Eigen::Vector3f::Zero();
  // A gentle bend (0.01 /mm, as straight hair's seen strands) is not a curl.
  for (int k = 0; k < 30; ++k)
    helix.Follow(Eigen::Vector3f(std::sin(0.01f * static_cast<float>(k)), 0,
                                 -std::cos(0.01f * static_cast<float>(k))));
  EXPECT_FALSE(helix.Continue(Eigen::Vector3f(0, 0, -1), Eigen::Vector3f(0, 0, -1), &next));
  EXPECT_EQ(next, Eigen::Vector3f::Zero());
}

// A wave in one plane (amplitude 1 mm, period 16 mm; its tangents up to 21 deg off its axis)
// bends as much as a curl, but about an axis that flips: carried on, the strand keeps near the
// field's direction instead of circling it.
TEST(HelixContinuation, KeepsAPlanarWaveNearTheField) {
  HelixContinuation helix({}, 1.0);
  const double k = 2 * M_PI / 16;
  for (int s = 0; s < 30; ++s)
    helix.Follow(Eigen::Vector3f(static_cast<float>(k * std::cos(k * s)), 0, -1).normalized());
  Eigen::Vector3f previous(0, 0, -1), next;
  const Eigen::Vector3f down(0, 0, -1);
  double worst = 0;
  for (int s = 0; s < 40; ++s) {
    ASSERT_TRUE(helix.Continue(previous, down, &next)) << "it bends as much as a curl";
    worst = std::max(worst, AngleDeg(next, down));
    previous = next;
  }
  EXPECT_LT(worst, 21.0);
}

// A window of 4 mm strays 0.3 mm from its mean direction on a curl of radius 5 mm: the curl's
// width is not seen, and the strand carried on turns no wider than twice that.
TEST(HelixContinuation, LoopsNoWiderThanTheWindowStrays) {
  HelixContinuationOptions options;
  options.window_mm = 4;
  HelixContinuation helix(options, 1.0);
  for (int s = 0; s < 4; ++s) helix.Follow(HelixTangent(s, 5, 3, 1));
  Eigen::Vector3f next;
  ASSERT_TRUE(helix.Continue(HelixTangent(4, 5, 3, 1), Eigen::Vector3f::UnitZ(), &next));
  EXPECT_LT(AngleDeg(next, Eigen::Vector3f::UnitZ()), 20.0);
}

TEST(HelixContinuation, NeedsAFullWindowAndStartsAgainAfterAGap) {
  HelixContinuation helix({}, 1.0);
  Eigen::Vector3f next;
  for (int k = 0; k < 8; ++k) helix.Follow(HelixTangent(k, 5, 3, 1));
  EXPECT_FALSE(helix.Continue(HelixTangent(8, 5, 3, 1), Eigen::Vector3f::UnitZ(), &next))
      << "half a window";
  for (int k = 8; k < 20; ++k) helix.Follow(HelixTangent(k, 5, 3, 1));
  ASSERT_TRUE(helix.Continue(HelixTangent(20, 5, 3, 1), Eigen::Vector3f::UnitZ(), &next));
  // Followed again after the unseen stretch: the old window is gone.
  helix.Follow(HelixTangent(40, 5, 3, 1));
  EXPECT_FALSE(helix.Continue(HelixTangent(41, 5, 3, 1), Eigen::Vector3f::UnitZ(), &next));
}

}  // namespace
}  // namespace hairrig
