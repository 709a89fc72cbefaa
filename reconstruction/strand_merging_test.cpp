#include "reconstruction/strand_merging.h"

#include <gtest/gtest.h>

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
  options.distance_mm = 0;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
  options.distance_mm = 0.1;
  options.run_mm = -1;
  EXPECT_EQ(options.Check().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
