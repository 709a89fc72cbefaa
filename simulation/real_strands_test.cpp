// The simulation core on the real strands of ../shared/data/strands. In an
// executable of their own: they skip (exit 77) when ../shared is absent, and
// that must not hide the synthetic tests beside them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/strand_io.h"
#include "simulation/floating_tangents.h"
#include "simulation/guides.h"
#include "simulation/inverse_statics.h"
#include "simulation/super_helix.h"
#include "simulation/super_helix_dynamics.h"

namespace hairrig {
namespace {

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
      for (size_t i = offsets[k]; i < offsets[k + 1]; ++i)
        p.push_back(strands->points_mm[i].cast<double>());
      StrandFitSummary s;
      auto model = FitFloatingTangents(p, o, &s);
      ASSERT_TRUE(model.ok()) << "strand " << k << ": " << model.status().ToString();
      mean_sum += s.mean_error_mm;
      worst = std::max(worst, s.max_error_mm);
      g1 = std::max(g1, s.max_g1_defect_deg);
      elements += s.elements;
      ++fitted;
    }
    std::printf(
        "Bangs_100, %s: %.2f elements per strand, mean error %.3f mm, max %.3f mm, G1 %.1e deg\n",
        variant.name, static_cast<double>(elements) / fitted, mean_sum / fitted, worst, g1);
    mean_of[v++] = mean_sum / fitted;
    EXPECT_LT(g1, 1e-3);
  }
  // Measured: paper 0.725 mm (these gently curved bangs get N_min = 3), ours
  // 0.040 mm with 17.1 elements, fixed N = 15 0.054 mm.
  EXPECT_LT(mean_of[0], 1.3);
  EXPECT_LT(mean_of[1], 0.08);
  EXPECT_LE(mean_of[1], mean_of[2]) << "ours is no worse than the fixed-N baseline";
  EXPECT_LT(mean_of[2], 0.1);
}

TEST(Guides, MoreGuidesLessErrorOnRealStrands) {
  const std::string path = "../shared/data/strands/Bangs_100.hair";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent beside the repository";
  auto strands = ReadStrands(path);
  ASSERT_TRUE(strands.ok());
  double previous = 1e9;
  for (int k : {1, 5, 20, 100}) {
    GuideOptions o;
    o.num_guides = k;
    auto g = SelectGuides(*strands, o);
    ASSERT_TRUE(g.ok());
    std::printf("Bangs_100, %3d guides: RMS distance to guide %.2f mm\n", k, g->rms_error_mm);
    EXPECT_LT(g->rms_error_mm, previous);
    previous = g->rms_error_mm;
  }
  EXPECT_NEAR(previous, 0, 1e-6) << "every strand its own guide";
}

// (d) A fitted real strand, after inverse statics, drifts less than 0.5 mm at
// its tip over 2 s under gravity; without inverse statics it sags by more
// than 2.5 mm. Measured: 0.34 mm for the longest strand, under 0.0001 mm for
// the other four; 5.3-105 mm without. The bangs
// hang along -x in their (CT scanner) frame, so that is down here.
TEST(InverseStatics, FittedRealStrandsDoNotSag) {
  const std::string path = "../shared/data/strands/Bangs_100.hair";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent beside the repository";
  auto strands = ReadStrands(path);
  ASSERT_TRUE(strands.ok());
  const auto offsets = strands->Offsets();
  const std::vector<double> lengths = strands->StrandLengths();
  std::vector<size_t> order(lengths.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return lengths[a] > lengths[b]; });
  Environment env;
  env.gravity_m_s2 = Eigen::Vector3d(-9.81, 0, 0);
  const HairMaterial material;
  const DynamicsOptions options;
  for (size_t k : {order[0], order[1], order[2], order[10], order[30]}) {
    std::vector<Eigen::Vector3d> points;
    for (size_t i = offsets[k]; i < offsets[k + 1]; ++i)
      points.push_back(strands->points_mm[i].cast<double>());
    auto fitted = FitFloatingTangents(points, FloatingTangentsOptions{});
    ASSERT_TRUE(fitted.ok()) << fitted.status().ToString();
    Eigen::VectorXd q;
    auto strand = SuperHelixFromPiecewiseHelix(*fitted, Eigen::Vector3d::UnitY(), &q);
    ASSERT_TRUE(strand.ok()) << strand.status().ToString();
    double drift[2];
    for (int with_statics = 0; with_statics < 2; ++with_statics) {
      SuperHelixDynamics dynamics(*strand, material, options);
      if (with_statics) {
        InverseStaticsReport report;
        ASSERT_TRUE(SolveInverseStatics(env, q, &dynamics, &report).ok());
        EXPECT_LT(report.residual_force, 1e-9);
      }
      StrandState state{q, Eigen::VectorXd::Zero(q.size())};
      const Eigen::Vector3d tip0 = TipPosition(*strand, q);
      double worst = 0;
      for (int step = 0; step < static_cast<int>(2.0 / options.time_step_s); ++step) {
        ASSERT_TRUE(dynamics.Step(env, &state).ok());
        worst = std::max(worst, (TipPosition(*strand, state.q) - tip0).norm());
      }
      drift[with_statics] = 1e3 * worst;
    }
    std::printf(
        "strand %zu (%.0f mm, %d elements): tip drift over 2 s %.4f mm with inverse statics, %.1f "
        "mm without\n",
        k, lengths[k], strand->num_elements(), drift[1], drift[0]);
    EXPECT_LT(drift[1], 0.5);
    if (lengths[k] > 60) {
      EXPECT_GT(drift[0], 2.5) << "without inverse statics a long strand sags";
    }
  }
}

}  // namespace
}  // namespace hairrig
