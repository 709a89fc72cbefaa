#include "reconstruction/strand_merging.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace hairrig {
namespace {

// A straight strand along +z from (x, 0, 0), `length` mm at 1 mm steps.
std::vector<Eigen::Vector3f> Straight(float x, float length) {
  std::vector<Eigen::Vector3f> strand;
  for (float z = 0; z <= length; z += 1) strand.emplace_back(x, 0, z);
  return strand;
}

// From (x, 0, 0) it bends over 20 mm onto the line x = 0 and follows it to z = 60.
std::vector<Eigen::Vector3f> JoiningAtZ20(float x) {
  std::vector<Eigen::Vector3f> strand;
  for (float z = 0; z <= 60; z += 1) strand.emplace_back(z < 20 ? x * (1 - z / 20) : 0.0f, 0, z);
  return strand;
}

TEST(EndMergedStrands, AStrandThatJoinsAnEarlierOneEndsWhereItJoins) {
  StrandSet strands;
  strands.AddStrand(Straight(0, 60));
  strands.AddStrand(JoiningAtZ20(5));
  strands.AddStrand(Straight(0.5f, 60));  // parallel, 0.5 mm away: not merged
  StrandMergeOptions options;
  options.run_mm = 10;
  StrandMergeSummary summary;
  const StrandSet out = EndMergedStrands(strands, options, &summary);
  ASSERT_EQ(out.num_strands(), 3u);
  EXPECT_EQ(out.point_counts[0], 61u);
  EXPECT_EQ(out.point_counts[1], 21u) << "kept up to z = 20, where it joined";
  EXPECT_NEAR(out.points_mm[61 + 20].z(), 20.0f, 1e-4f);
  EXPECT_EQ(out.point_counts[2], 61u);
  EXPECT_EQ(summary.strands_ended, 1);
  EXPECT_EQ(summary.strands_dropped, 0);
  EXPECT_EQ(summary.vertices_removed, 40);
}

TEST(EndMergedStrands, TheSameLineSampledHalfAStepApartHasMerged) {
  StrandSet strands;
  strands.AddStrand(Straight(0, 60));
  std::vector<Eigen::Vector3f> shifted = Straight(0, 59);
  for (Eigen::Vector3f& p : shifted) p.z() += 0.5f;
  strands.AddStrand(shifted);
  StrandMergeOptions options;
  options.run_mm = 10;
  StrandMergeSummary summary;
  const StrandSet out = EndMergedStrands(strands, options, &summary);
  EXPECT_EQ(out.num_strands(), 1u) << "on the first strand from its root: dropped";
  EXPECT_EQ(summary.strands_dropped, 1);
  EXPECT_EQ(summary.vertices_removed, 60);
}

// Strands in random directions through a box 6 mm wide, some of them
// crossing: a strand is cut exactly where a brute-force search over the
// earlier strands' kept pieces finds a run of run_mm within the distance.
TEST(EndMergedStrands, AgreesWithABruteForceSearch) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-3, 3);
  StrandSet strands;
  for (int k = 0; k < 60; ++k) {
    const Eigen::Vector3f start(u(rng), u(rng), u(rng) - 40.0f);
    const Eigen::Vector3f step = (Eigen::Vector3f(0.02f * u(rng), 0.02f * u(rng), 1)).normalized();
    std::vector<Eigen::Vector3f> strand;
    for (int i = 0; i < 80; ++i) strand.push_back(start + static_cast<float>(i) * step);
    // Every 4th strand runs along the first one for a while (a merge).
    if (k % 4 == 3)
      for (int i = 30; i < 80; ++i) strand[i] = strands.points_mm[i] + Eigen::Vector3f(0.03f, 0, 0);
    strands.AddStrand(strand);
  }
  StrandMergeOptions options;
  options.distance_mm = 0.1;
  options.run_mm = 5;
  const StrandSet out = EndMergedStrands(strands, options);
  // Brute force, in the same order.
  std::vector<std::vector<Eigen::Vector3f>> kept;
  const std::vector<size_t> offsets = strands.Offsets();
  for (size_t k = 0; k < strands.num_strands(); ++k) {
    const std::vector<Eigen::Vector3f> strand(strands.points_mm.begin() + offsets[k],
                                              strands.points_mm.begin() + offsets[k + 1]);
    const auto on_earlier = [&](const Eigen::Vector3f& p) {
      for (const auto& other : kept)
        for (size_t i = 1; i < other.size(); ++i) {
          const Eigen::Vector3f ab = other[i] - other[i - 1];
          const float t = std::clamp((p - other[i - 1]).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f);
          if ((other[i - 1] + t * ab - p).norm() < 0.1f) return true;
        }
      return false;
    };
    size_t keep = strand.size(), start = 0;
    double run = -1;
    for (size_t i = 0; i < strand.size() && keep == strand.size(); ++i) {
      if (!on_earlier(strand[i])) {
        run = -1;
      } else if (run < 0) {
        run = 0, start = i;
      } else if ((run += (strand[i] - strand[i - 1]).norm()) >= 5) {
        keep = start + 1;
      }
    }
    if (keep >= 2) kept.emplace_back(strand.begin(), strand.begin() + keep);
  }
  ASSERT_EQ(out.num_strands(), kept.size());
  int merged = 0;
  for (size_t k = 0; k < kept.size(); ++k) {
    EXPECT_EQ(out.point_counts[k], kept[k].size()) << "strand " << k;
    merged += kept[k].size() < 80 ? 1 : 0;
  }
  EXPECT_GE(merged, 15) << "the strands built to merge did";
}

TEST(EndMergedStrands, ShortContactsAndTheOffSwitchLeaveStrandsWhole) {
  StrandSet strands;
  strands.AddStrand(Straight(0, 60));
  // Crosses x = 0 at z = 30 at 45 deg: a contact of about one vertex.
  std::vector<Eigen::Vector3f> crossing;
  for (float z = 0; z <= 60; z += 1) crossing.emplace_back(z - 30, 0, z);
  strands.AddStrand(crossing);
  StrandMergeOptions options;
  options.run_mm = 10;
  StrandMergeSummary summary;
  EXPECT_EQ(EndMergedStrands(strands, options, &summary).num_points(), strands.num_points());
  EXPECT_EQ(summary.strands_ended, 0);
  strands.AddStrand(JoiningAtZ20(3));
  options.run_mm = 0;
  EXPECT_EQ(EndMergedStrands(strands, options, &summary).num_points(), strands.num_points());
}

TEST(EndMergedStrands, ADuplicateFromItsRootIsDropped) {
  StrandSet strands;
  strands.AddStrand(Straight(0, 30));
  strands.AddStrand(Straight(0.05f, 30));
  StrandMergeOptions options;
  options.run_mm = 10;
  StrandMergeSummary summary;
  const StrandSet out = EndMergedStrands(strands, options, &summary);
  ASSERT_EQ(out.num_strands(), 1u);
  EXPECT_EQ(summary.strands_dropped, 1);
}

TEST(StrandMergeOptions, BadValuesAreRefused) {
  StrandMergeOptions options;
  for (const double distance : {0.0, 0.001, 50.0}) {
    options.distance_mm = distance;
    EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument) << distance;
  }
  options.distance_mm = 0.1;
  options.run_mm = -1;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
