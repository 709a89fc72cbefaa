#include "simulation/floating_tangents.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "simulation/strand_spline.h"

namespace hairrig {
namespace {

std::vector<Eigen::Vector3d> HelixPoints(double radius, double pitch, double turns, int n) {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * turns * i / (n - 1);
    p.emplace_back(radius * std::cos(a), radius * std::sin(a), -pitch * a / (2 * M_PI));
  }
  return p;
}

TEST(StrandSpline, ArcLengthMatchesTheCurve) {
  // A quarter circle of radius 100 mm through 30 points: length 157.08 mm.
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 30; ++i) {
    const double a = M_PI / 2 * i / 29;
    p.emplace_back(100 * std::cos(a), 100 * std::sin(a), 0);
  }
  auto spline = StrandSpline::Create(p);
  ASSERT_TRUE(spline.ok());
  EXPECT_NEAR(spline->length_mm(), 50 * M_PI, 0.01);
  EXPECT_NEAR((spline->PointAt(spline->length_mm() / 2) -
               Eigen::Vector3d(100 / std::sqrt(2), 100 / std::sqrt(2), 0))
                  .norm(),
              0, 0.01);
  EXPECT_NEAR(spline->TangentAt(0).dot(Eigen::Vector3d::UnitY()), 1, 1e-3);
  EXPECT_FALSE(StrandSpline::Create({{0, 0, 0}, {0, 0, 0}}).ok()) << "zero length";
  EXPECT_FALSE(StrandSpline::Create({{0, 0, 0}, {NAN, 0, 0}}).ok()) << "NaN";
}

TEST(FloatingTangents, HelicalStrandIsFollowedClosely) {
  FloatingTangentsOptions o;
  StrandFitSummary s;
  auto model = FitFloatingTangents(HelixPoints(5, 14, 6, 400), o, &s);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  EXPECT_LT(s.mean_error_mm, 0.05);
  EXPECT_LT(s.max_g1_defect_deg, 1e-4);
  EXPECT_LT(s.max_cohelical_residual, 1e-9);
  EXPECT_NEAR(model->length_mm(), s.strand_length_mm, 0.01 * s.strand_length_mm);
  for (const auto& e : model->elements) {
    EXPECT_NEAR(e.curvature_per_mm(), 5 / (25 + std::pow(14 / (2 * M_PI), 2)), 0.01)
        << "curl curvature r/(r^2+c^2)";
  }
}

TEST(FloatingTangents, StraightStrandGetsTheMinimumOfStraightElements) {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i <= 40; ++i) p.emplace_back(0, 0, -5.0 * i);
  StrandFitSummary s;
  auto model = FitFloatingTangents(p, {}, &s);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  EXPECT_EQ(s.elements, 3);
  EXPECT_LT(s.max_error_mm, 1e-9);
  for (const auto& e : model->elements) EXPECT_EQ(e.curvature_per_mm(), 0);
}

// Without a summary the fit error is measured only where the growth needs it;
// the model must not change.
TEST(FloatingTangents, TheModelIsTheSameWithOrWithoutASummary) {
  std::vector<Eigen::Vector3d> bent;
  for (int i = 0; i <= 60; ++i) bent.emplace_back(40 * (1 - std::cos(0.02 * i)), 0, -5.0 * i);
  auto bent_spline = StrandSpline::Create(bent);
  ASSERT_TRUE(bent_spline.ok());
  const int algorithm2 = AdaptiveElementCount(*bent_spline, {});
  for (const auto& points : {bent, HelixPoints(5, 14, 6, 400)}) {
    StrandFitSummary s;
    auto reported = FitFloatingTangents(points, {}, &s);
    auto alone = FitFloatingTangents(points, {});
    ASSERT_TRUE(reported.ok() && alone.ok());
    ASSERT_EQ(reported->elements.size(), alone->elements.size());
    for (size_t k = 0; k < alone->elements.size(); ++k) {
      EXPECT_EQ(reported->elements[k].length_mm, alone->elements[k].length_mm) << k;
      EXPECT_EQ(reported->elements[k].darboux_per_mm, alone->elements[k].darboux_per_mm) << k;
    }
  }
  StrandFitSummary bent_fit;
  ASSERT_TRUE(FitFloatingTangents(bent, {}, &bent_fit).ok());
  EXPECT_GT(bent_fit.elements, algorithm2)
      << "the bent strand's growth (which needs the error) took part";
  EXPECT_LT(bent_fit.elements, 25) << "and stopped below N_max, at the target";
}

// A curl whose radius grows from 0 at the root over `ramp_mm` of its axis
// (as the simulated wig's curls do), radius and pitch in mm, `fibre_mm` long.
std::vector<Eigen::Vector3d> RampedCurl(double fibre_mm, double radius, double pitch,
                                        double ramp_mm) {
  std::vector<Eigen::Vector3d> p;
  const double axis_length = fibre_mm / std::hypot(1.0, 2 * M_PI * radius / pitch);
  for (double u = 0; u <= axis_length; u += pitch / 16) {
    const double r = radius * std::min(1.0, u / ramp_mm), phase = 2 * M_PI * u / pitch;
    p.emplace_back(r * std::cos(phase), r * std::sin(phase), -u);
  }
  return p;
}

// When the growth ends at N_max with a relaxation that moves a break point
// by more than a quarter element (a resonance of the co-helical conditions),
// ours takes one element fewer if that relaxes less.
TEST(FloatingTangents, OneElementFewerWhenTheRelaxationResonatesAtNmax) {
  const auto curl = RampedCurl(400, 5, 14, 60);
  FloatingTangentsOptions fixed, ours;
  fixed.adaptive = false;
  fixed.fixed_elements = ours.max_elements = 18;
  StrandFitSummary at_max, chosen;
  ASSERT_TRUE(FitFloatingTangents(curl, fixed, &at_max).ok());
  ASSERT_GT(at_max.max_relaxation_elements, 0.25) << "the case must resonate at N_max";
  ASSERT_TRUE(FitFloatingTangents(curl, ours, &chosen).ok());
  EXPECT_EQ(chosen.elements, 17);
  EXPECT_LT(chosen.max_relaxation_elements, at_max.max_relaxation_elements);
  EXPECT_LE(chosen.mean_error_mm, at_max.mean_error_mm);
}

// The pruned distance equals a brute-force one.
TEST(FloatingTangents, DistanceToCurveIsExact) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-50, 50);
  std::vector<Eigen::Vector3d> curve, points;
  for (int i = 0; i < 300; ++i)
    curve.emplace_back(u(rng) * 0.1 + i, u(rng) * 0.1, std::sin(i * 0.1) * 20);
  for (int i = 0; i < 80; ++i) points.emplace_back(u(rng) + 150, u(rng), u(rng));
  double mean = 0, max = 0;
  DistanceToCurve(points, curve, &mean, &max);
  double brute_sum = 0, brute_max = 0;
  for (const auto& q : points) {
    double best = 1e300;
    for (size_t k = 0; k + 1 < curve.size(); ++k) {
      const Eigen::Vector3d seg = curve[k + 1] - curve[k];
      const double t = std::clamp((q - curve[k]).dot(seg) / seg.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (curve[k] + t * seg - q).norm());
    }
    brute_sum += best;
    brute_max = std::max(brute_max, best);
  }
  EXPECT_NEAR(mean, brute_sum / static_cast<double>(points.size()), 1e-12);
  EXPECT_NEAR(max, brute_max, 1e-12);
}

// Elements that turn by more than pi (coils) when the strand is fitted with
// each of two option sets, and the two fits' summaries.
struct CoilComparison {
  int coils[2] = {-1, -1};
  StrandFitSummary fits[2];
};
CoilComparison CompareCoils(const std::vector<Eigen::Vector3d>& points,
                            const FloatingTangentsOptions& first,
                            const FloatingTangentsOptions& second) {
  CoilComparison c;
  const FloatingTangentsOptions* options[2] = {&first, &second};
  for (int k = 0; k < 2; ++k) {
    auto model = FitFloatingTangents(points, *options[k], &c.fits[k]);
    if (!model.ok()) {
      ADD_FAILURE() << model.status().ToString();
      continue;
    }
    c.coils[k] = 0;
    for (const auto& e : model->elements)
      c.coils[k] += e.darboux_per_mm.norm() * e.length_mm > M_PI;
  }
  return c;
}

// A gently bent strand with 0.05 mm of noise: the co-helical pairs of its
// nearly straight elements lean too far for a short rotation, so the plain
// relaxation joins many of them by coils (helices turning by more than pi);
// with planar_arcs those become planar arcs.
TEST(FloatingTangents, PlanarArcsReplaceTheCoilsOfNoisyStraightStretches) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.05);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i <= 60; ++i) {
    const double a = 0.02 * i;
    p.emplace_back(100 * (1 - std::cos(a)) + noise(rng), noise(rng),
                   -100 * std::sin(a) + noise(rng));
  }
  FloatingTangentsOptions planar;
  planar.planar_arcs = true;
  const CoilComparison c = CompareCoils(p, FloatingTangentsOptions{}, planar);
  EXPECT_GE(c.coils[0], 8);
  EXPECT_LE(c.coils[1], 2);
  EXPECT_LT(c.fits[1].max_g1_defect_deg, 1e-4);
  EXPECT_LT(c.fits[1].mean_error_mm, 0.5) << "the arcs stay within the noise's reach";
}

// A strand that leaves the scalp sideways, bends down within 20 mm and then
// hangs straight, stored in single precision as strand files are: the
// rounding (~1e-5 mm) tilts the chords of the straight elements a little, and
// their nearly parallel tangents then admit only coils (a full turn of high
// torsion per element). Straight runs (the default) make them straight.
TEST(FloatingTangents, StraightRunsReplaceTheCoilsOfRoundingNoise) {
  std::vector<Eigen::Vector3d> p;
  const Eigen::Vector3d root(83.1, -41.7, 112.9),
      down = Eigen::Vector3d(0.05, 0.02, -1).normalized();
  Eigen::Vector3d point = root;
  for (int i = 0; i <= 80; ++i) {
    const double w = std::exp(-5.0 * i / 8);
    const Eigen::Vector3d tangent = (w * Eigen::Vector3d::UnitX() + (1 - w) * down).normalized();
    p.push_back(point.cast<float>().cast<double>());
    point += 5 * tangent;
  }
  FloatingTangentsOptions plain;
  plain.straight_sagitta_mm = 0;
  const CoilComparison c = CompareCoils(p, plain, FloatingTangentsOptions{});
  EXPECT_GE(c.coils[0], 5);
  EXPECT_EQ(c.coils[1], 0);
  EXPECT_LT(c.fits[1].max_g1_defect_deg, 1e-4);
  EXPECT_LT(c.fits[1].mean_error_mm, c.fits[0].mean_error_mm + 0.05);
  FloatingTangentsOptions bad;
  bad.straight_sagitta_mm = -1;
  EXPECT_FALSE(FitFloatingTangents(p, bad).ok());
}

// A tight curl (radius 2 mm, pitch 5 mm, 14 turns): Algorithm 2's 14 tangent
// samples are a turn apart and see no curl; ours starts at one element per
// quarter turn (up to N_max) before any error-driven growth.
TEST(FloatingTangents, CurlsStartAtAnElementPerQuarterTurn) {
  const std::vector<Eigen::Vector3d> curl = HelixPoints(2, 5, 14, 700);
  auto spline = StrandSpline::Create(curl);
  ASSERT_TRUE(spline.ok());
  EXPECT_NEAR(spline->turning_rad(), 14 * 2 * M_PI * 2 * M_PI * 2 / std::hypot(2 * M_PI * 2, 5),
              0.5)
      << "the tangent turns by k L = 2 pi r / sqrt((2 pi r)^2 + c^2) per turn";
  FloatingTangentsOptions paper, ours;
  paper.target_mean_error_mm = 0;
  ours.target_mean_error_mm = 1e9;  // no error-driven growth: the starting N alone
  StrandFitSummary paper_fit, ours_fit;
  ASSERT_TRUE(FitFloatingTangents(curl, paper, &paper_fit).ok());
  ASSERT_TRUE(FitFloatingTangents(curl, ours, &ours_fit).ok());
  EXPECT_EQ(paper_fit.elements, AdaptiveElementCount(*spline, paper));
  EXPECT_LT(paper_fit.elements, 20);
  const int quarter_turns = static_cast<int>(std::ceil(spline->turning_rad() / (M_PI / 2)));
  EXPECT_EQ(ours_fit.elements,
            std::min(ours.max_elements, std::max(paper_fit.elements, quarter_turns)));
  EXPECT_GT(ours_fit.elements, paper_fit.elements);
}

TEST(FloatingTangents, BadInputIsRefused) {
  EXPECT_FALSE(FitFloatingTangents({{0, 0, 0}}, {}).ok());
  FloatingTangentsOptions bad;
  bad.max_elements = 0;
  EXPECT_FALSE(FitFloatingTangents(HelixPoints(5, 14, 1, 50), bad).ok());
}

}  // namespace
}  // namespace hairrig
