#include "simulation/guides.h"

#include <gtest/gtest.h>

#include <random>

namespace hairrig {
namespace {

// Three bundles of 30 strands hanging from three roots, with 0.5 mm jitter.
StrandSet ThreeBundles() {
  StrandSet set;
  std::mt19937 rng(3);
  std::normal_distribution<float> jitter(0, 0.5f);
  const Eigen::Vector3f roots[3] = {{0, 0, 0}, {60, 0, 0}, {0, 60, 0}};
  for (int b = 0; b < 3; ++b) {
    for (int s = 0; s < 30; ++s) {
      std::vector<Eigen::Vector3f> p;
      for (int k = 0; k < 20; ++k) {
        p.push_back(roots[b] + Eigen::Vector3f(jitter(rng), jitter(rng),
                                               -5.0f * static_cast<float>(k) + jitter(rng)));
      }
      set.AddStrand(p);
    }
  }
  return set;
}

TEST(Guides, ResampleByArcLengthIsEvenlySpaced) {
  const std::vector<Eigen::Vector3f> p = {{0, 0, 0}, {1, 0, 0}, {10, 0, 0}};
  const auto r = ResampleByArcLength(p.data(), p.size(), 11);
  for (int k = 0; k < 11; ++k) EXPECT_NEAR(r[static_cast<size_t>(k)].x(), k, 1e-5);
}

TEST(Guides, OneGuidePerBundle) {
  const StrandSet set = ThreeBundles();
  GuideOptions o;
  o.num_guides = 3;
  auto g = SelectGuides(set, o);
  ASSERT_TRUE(g.ok()) << g.status().ToString();
  ASSERT_EQ(g->guide_strands.size(), 3u);
  for (int s = 0; s < 90; ++s) {
    // Strands of one bundle share a cluster, and its guide is from that bundle.
    EXPECT_EQ(g->cluster_of_strand[static_cast<size_t>(s)],
              g->cluster_of_strand[static_cast<size_t>(s / 30 * 30)]);
    EXPECT_EQ(
        g->guide_strands[static_cast<size_t>(g->cluster_of_strand[static_cast<size_t>(s)])] / 30,
        s / 30);
  }
  EXPECT_LT(g->rms_error_mm, 1.5);
}

TEST(Guides, TargetErrorChoosesK) {
  GuideOptions o;
  o.target_rms_mm = 2.0;
  auto g = SelectGuides(ThreeBundles(), o);
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->guide_strands.size(), 3u) << "three bundles meet a 2 mm target";
  EXPECT_LE(g->max_cluster_rms_mm, 2.0);
  o.num_guides = 91;
  EXPECT_FALSE(SelectGuides(ThreeBundles(), o).ok()) << "more guides than strands";
  EXPECT_FALSE(SelectGuides(StrandSet{}, GuideOptions{}).ok()) << "empty model";
}

}  // namespace
}  // namespace hairrig
