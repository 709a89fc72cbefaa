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
  // Measured: paper 0.82 mm (these gently curved bangs get N_min = 3), ours
  // 0.039 mm, fixed N = 15 0.053 mm.
  EXPECT_LT(mean_of[0], 1.3);
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

}  // namespace
}  // namespace hairrig
