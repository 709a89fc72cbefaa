#include "simulation/helix.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace hairrig {
namespace {

HelixElement Reference(double k, double tau, double length) {
  return HelixFromCurvatureTorsion({1, 2, 3}, Eigen::Vector3d(0.3, -0.2, 1).normalized(),
                                   Eigen::Vector3d(0.3, -0.2, 1).normalized().unitOrthogonal(), k,
                                   tau, length);
}

// Eq. 8 against the definition: r' = t, |t| = 1, |r''| = k.
TEST(Helix, Equation8IsAUnitSpeedCurveWithTheGivenCurvatureAndTorsion) {
  const HelixElement h = Reference(0.05, -0.02, 60);
  EXPECT_NEAR(h.curvature_per_mm(), 0.05, 1e-12);
  EXPECT_NEAR(h.torsion_per_mm(), -0.02, 1e-12);
  const double ds = 1e-4;
  for (double s : {0.0, 7.5, 33.0, 60.0}) {
    const Eigen::Vector3d derivative = (h.PointAt(s + ds) - h.PointAt(s - ds)) / (2 * ds);
    EXPECT_NEAR((derivative - h.TangentAt(s)).norm(), 0, 1e-7) << s;
    EXPECT_NEAR(h.TangentAt(s).norm(), 1, 1e-12);
    const Eigen::Vector3d second = (h.TangentAt(s + ds) - h.TangentAt(s - ds)) / (2 * ds);
    EXPECT_NEAR(second.norm(), 0.05, 1e-7) << s;
  }
}

// An exact helix is recovered with one element to 1e-6 relative.
TEST(Helix, ExactHelixIsRecoveredFromItsEndsToOnePartPerMillion) {
  struct Case {
    double k, tau, length;
  };
  for (const Case c :
       {Case{0.05, 0.02, 60}, Case{0.05, -0.02, 60}, Case{0.2, 0.1, 25}, Case{0.002, 0.001, 300},
        Case{0.1, 0.0, 40}, Case{0.15, 0.3, 30}, Case{0.08, 0.01, 70}, Case{0.15, 0.05, 26},
        Case{0.17, 0.06, 33},      // long rotations: 1.3 and 1.9 pi
        Case{0.18, 0.07, 200}}) {  // the last: a curl of about six turns
    const HelixElement truth = Reference(c.k, c.tau, c.length);
    auto fitted = HelixThrough(truth.start_mm, truth.start_tangent, truth.PointAt(c.length),
                               truth.TangentAt(c.length), c.length);
    ASSERT_TRUE(fitted.ok()) << fitted.status().ToString() << " k " << c.k << " tau " << c.tau;
    EXPECT_NEAR(fitted->curvature_per_mm(), c.k, 1e-6 * c.k) << "k " << c.k << " tau " << c.tau;
    EXPECT_NEAR(fitted->torsion_per_mm(), c.tau, 1e-6 * std::max(std::abs(c.tau), c.k))
        << "k " << c.k;
    EXPECT_NEAR(fitted->length_mm, c.length, 1e-6 * c.length) << "k " << c.k << " tau " << c.tau;
  }
}

// The short and the long rotation are found without the scan: each exact
// helix that turns by less than 2 pi is among HelicesWithoutExtraTurn's, and
// every helix it returns joins the two ends.
TEST(Helix, ShortAndLongRotationsAreFoundWithoutTheScan) {
  struct Case {
    double k, tau, length;
    bool long_rotation;
  };
  for (const Case c :
       {Case{0.05, 0.02, 30, false}, Case{0.1, 0.0, 20, false}, Case{0.15, 0.05, 26, true},
        Case{0.17, 0.06, 33, true}, Case{0.1, 0.08, 45, true}}) {
    const HelixElement truth = Reference(c.k, c.tau, c.length);
    const double turn = truth.darboux_per_mm.norm() * c.length;
    ASSERT_EQ(turn > M_PI, c.long_rotation) << "the case's turn is " << turn << " rad";
    const Eigen::Vector3d end = truth.PointAt(c.length), end_tangent = truth.TangentAt(c.length);
    const auto helices =
        HelicesWithoutExtraTurn(truth.start_mm, truth.start_tangent, end, end_tangent);
    int matches = 0;
    for (const HelixElement& h : helices) {
      EXPECT_LT((h.PointAt(h.length_mm) - end).norm(), 1e-6 * c.length) << "k " << c.k;
      EXPECT_LT((h.TangentAt(h.length_mm) - end_tangent).norm(), 1e-6) << "k " << c.k;
      EXPECT_LT(h.darboux_per_mm.norm() * h.length_mm, 2 * M_PI) << "no extra turn, k " << c.k;
      matches += std::abs(h.length_mm - c.length) < 1e-6 * c.length &&
                 std::abs(h.curvature_per_mm() - c.k) < 1e-6 * c.k &&
                 std::abs(h.torsion_per_mm() - c.tau) < 1e-6 * c.k;
    }
    EXPECT_EQ(matches, 1) << "k " << c.k << " tau " << c.tau << " length " << c.length << ": "
                          << helices.size() << " helices";
  }
  const Eigen::Vector3d t = Eigen::Vector3d::UnitX();
  EXPECT_TRUE(HelicesWithoutExtraTurn({0, 0, 0}, t, {1, 2, 0}, Eigen::Vector3d::UnitY()).empty())
      << "not co-helical";
}

TEST(Helix, SamplesByRecurrenceFollowEquation8) {
  const HelixElement h = Reference(0.15, 0.3, 30);  // more than a turn
  std::vector<Eigen::Vector3d> samples;
  h.AppendSamples(90, &samples);
  ASSERT_EQ(samples.size(), 90u);
  for (int k = 1; k <= 90; ++k) {
    EXPECT_NEAR((samples[static_cast<size_t>(k - 1)] - h.PointAt(30.0 * k / 90)).norm(), 0, 1e-12)
        << k;
  }
  HelixElement straight = h;
  straight.darboux_per_mm.setZero();
  samples.clear();
  straight.AppendSamples(3, &samples);
  EXPECT_NEAR((samples.back() - straight.PointAt(30)).norm(), 0, 1e-12);
}

// The short rotation exists for a planar arc (chord along t0 + t1) and not
// when nearly equal tangents meet a chord leaning sideways (only a coil joins
// them); HelixThrough then returns the arc, not a coil of similar length.
TEST(Helix, ShortRotationForArcsNotForLeaningChords) {
  const HelixElement arc = Reference(0.05, 0.0, 20);
  const Eigen::Vector3d chord = arc.PointAt(20) - arc.start_mm;
  const Eigen::Vector3d t1 = arc.TangentAt(20);
  EXPECT_TRUE(ShortRotationExists(chord, arc.start_tangent, t1));
  auto fitted = HelixThrough(arc.start_mm, arc.start_tangent, arc.PointAt(20), t1, 20.3);
  ASSERT_TRUE(fitted.ok());
  EXPECT_NEAR(fitted->torsion_per_mm(), 0, 1e-9);
  EXPECT_NEAR(fitted->length_mm, 20, 1e-9);
  const Eigen::Vector3d t = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d tilted = Eigen::Vector3d(1e-4, 0, 1).normalized();
  EXPECT_FALSE(ShortRotationExists(Eigen::Vector3d(0, 0.01, 10), t, tilted));
}

TEST(Helix, StraightAndImpossibleCases) {
  const Eigen::Vector3d t = Eigen::Vector3d::UnitX();
  auto straight = HelixThrough({0, 0, 0}, t, {10, 0, 0}, t);
  ASSERT_TRUE(straight.ok());
  EXPECT_DOUBLE_EQ(straight->length_mm, 10);
  EXPECT_DOUBLE_EQ(straight->curvature_per_mm(), 0);
  EXPECT_FALSE(HelixThrough({0, 0, 0}, t, {0, 10, 0}, t).ok())
      << "equal tangents, chord across them";
  EXPECT_FALSE(HelixThrough({0, 0, 0}, t, {0, 0, 0}, Eigen::Vector3d::UnitY()).ok())
      << "coincident points";
  auto not_cohelical = HelixThrough({0, 0, 0}, t, {1, 2, 0}, Eigen::Vector3d::UnitY());
  ASSERT_FALSE(not_cohelical.ok());
  EXPECT_NE(not_cohelical.status().message().find("co-helical"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
