#include "simulation/floating_tangents.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <algorithm>
#include <filesystem>
#include <random>

#include "core/strand_io.h"
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

// The pruned distance equals a brute-force one.
TEST(FloatingTangents, DistanceToCurveIsExact) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-50, 50);
  std::vector<Eigen::Vector3d> curve, points;
  for (int i = 0; i < 300; ++i) curve.emplace_back(u(rng) * 0.1 + i, u(rng) * 0.1, std::sin(i * 0.1) * 20);
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

TEST(FloatingTangents, BadInputIsRefused) {
  EXPECT_FALSE(FitFloatingTangents({{0, 0, 0}}, {}).ok());
  FloatingTangentsOptions bad;
  bad.max_elements = 0;
  EXPECT_FALSE(FitFloatingTangents(HelixPoints(5, 14, 1, 50), bad).ok());
}

// Real strands (CT2Hair bangs, ../shared): every strand fits, G1 by
// construction, with the paper's adaptive N and with the fixed N = 15 baseline.
TEST(FloatingTangents, RealStrandsFitAdaptiveAndFixed) {
  const std::string path = "../shared/data/strands/Bangs_100.hair";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent beside the repository";
  auto strands = ReadStrands(path);
  ASSERT_TRUE(strands.ok()) << strands.status().ToString();
  const auto offsets = strands->Offsets();
  struct Variant {
    const char* name;
    bool adaptive;
    double target_mm;
  };
  double mean_of[3] = {0, 0, 0};
  int v = 0;
  for (const Variant variant : {Variant{"adaptive N, Algorithm 2 (paper)", true, 0.0},
                                Variant{"adaptive N, error target 0.05 mm (ours)", true, 0.05},
                                Variant{"fixed N = 15 (Table 2 baseline)", false, 0.0}}) {
    FloatingTangentsOptions o;
    o.adaptive = variant.adaptive;
    o.target_mean_error_mm = variant.target_mm;
    double mean_sum = 0, worst = 0, g1 = 0;
    int fitted = 0, elements = 0;
    for (size_t k = 0; k < strands->num_strands(); ++k) {
      std::vector<Eigen::Vector3d> p;
      for (size_t i = offsets[k]; i < offsets[k + 1]; ++i) p.push_back(strands->points_mm[i].cast<double>());
      StrandFitSummary s;
      auto model = FitFloatingTangents(p, o, &s);
      ASSERT_TRUE(model.ok()) << "strand " << k << ": " << model.status().ToString();
      mean_sum += s.mean_error_mm;
      worst = std::max(worst, s.max_error_mm);
      g1 = std::max(g1, s.max_g1_defect_deg);
      elements += s.elements;
      ++fitted;
    }
    std::printf("Bangs_100, %s: %.2f elements per strand, mean error %.3f mm, max %.3f mm, G1 %.1e deg\n",
                variant.name, static_cast<double>(elements) / fitted, mean_sum / fitted, worst, g1);
    mean_of[v++] = mean_sum / fitted;
    EXPECT_LT(g1, 1e-3);
  }
  // Measured: paper 0.82 mm (these gently curved bangs get N_min = 3), ours
  // 0.039 mm, fixed N = 15 0.053 mm.
  EXPECT_LT(mean_of[0], 1.3);
  EXPECT_LE(mean_of[1], mean_of[2]) << "ours is no worse than the fixed-N baseline";
  EXPECT_LT(mean_of[2], 0.1);
}

}  // namespace
}  // namespace hairrig
