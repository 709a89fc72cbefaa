#include "reconstruction/segment_coverage.h"

#include <gtest/gtest.h>

#include <vector>

namespace hairrig {
namespace {

// A straight polyline along +x from x0 to x1 at (y, z), vertices 1 mm apart.
std::vector<Eigen::Vector3f> AlongX(float x0, float x1, float y, float z) {
  std::vector<Eigen::Vector3f> points;
  const float step = x1 > x0 ? 1.f : -1.f;
  for (float x = x0; step > 0 ? x <= x1 : x >= x1; x += step) points.emplace_back(x, y, z);
  return points;
}

TEST(StrandCoverage, ASegmentIsCoveredWhereAStrandRunsBesideItTheSameWay) {
  StrandCoverage coverage(CoverageOptions{});  // 1.5 mm, 30 deg
  coverage.Add(AlongX(0, 20, 0, 0));
  EXPECT_NEAR(coverage.UncoveredLengthMm({AlongX(0, 20, 1, 0)}), 0, 1e-6) << "1 mm beside it";
  EXPECT_NEAR(coverage.UncoveredLengthMm({AlongX(0, 20, 0, 2)}), 20, 1e-6) << "2 mm beside it";
  EXPECT_NEAR(coverage.UncoveredLengthMm({AlongX(20, 0, 1, 0)}), 20, 1e-6) << "the other way";
  // Half of it past the strand's end: the vertex at x = 21 still lies within
  // 1.5 mm of the strand's last one (1.41 mm), so the uncovered edges run
  // from x = 22 to 40, and the edge from 21 to 22 counts half.
  EXPECT_NEAR(coverage.UncoveredLengthMm({AlongX(0, 40, 1, 0)}), 18.5, 1e-6);
}

TEST(StrandCoverage, NearestFindsTheClosestVertexWithinItsReachAndAngle) {
  StrandCoverage coverage(CoverageOptions{});
  StrandSet strands;
  strands.AddStrand(AlongX(0, 20, 0, 0));
  strands.AddStrand(AlongX(0, 20, 5, 0));
  coverage.Add(strands);
  coverage.Add(AlongX(20, 0, 3, 0));  // the third strand, running -x
  const Eigen::Vector3f along_x(1, 0, 0);
  StrandCoverage::Vertex v = coverage.Nearest({7.2f, 3.9f, 0}, along_x, 8, 0.5);
  EXPECT_EQ(v.strand, 1) << "the +x strand at y = 5, not the nearer -x one at y = 3";
  EXPECT_EQ(v.vertex, 7);
  v = coverage.Nearest({7.2f, 3.1f, 0}, -along_x, 8, 0.5);
  EXPECT_EQ(v.strand, 2);
  EXPECT_EQ(v.vertex, 13) << "x = 7 on the strand from x = 20 down";
  EXPECT_EQ(coverage.Nearest({7, 14, 0}, along_x, 8, 0.5).strand, -1) << "9 mm away";
}

}  // namespace
}  // namespace hairrig
