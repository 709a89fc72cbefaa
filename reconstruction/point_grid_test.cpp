#include "reconstruction/point_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace hairrig {
namespace {

// Points in clusters around `centres`, 1 mm apart on average.
std::vector<Eigen::Vector3f> Clusters(const std::vector<Eigen::Vector3f>& centres, int per_cluster,
                                      uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> offset(-10.0f, 10.0f);
  std::vector<Eigen::Vector3f> points;
  for (const Eigen::Vector3f& c : centres)
    for (int k = 0; k < per_cluster; ++k)
      points.push_back(c + Eigen::Vector3f(offset(rng), offset(rng), offset(rng)));
  return points;
}

std::vector<uint32_t> BruteForceWithin(const std::vector<Eigen::Vector3f>& points,
                                       const Eigen::Vector3f& q, double radius) {
  std::vector<uint32_t> within;
  for (uint32_t i = 0; i < points.size(); ++i)
    if ((points[i] - q).cast<double>().squaredNorm() <= radius * radius) within.push_back(i);
  return within;
}

// Every query of the grid against brute force, at radii below, at and above the cell.
void ExpectQueriesMatchBruteForce(const std::vector<Eigen::Vector3f>& points, double cell,
                                  const std::vector<Eigen::Vector3f>& queries) {
  const PointGrid grid(points, cell);
  for (const Eigen::Vector3f& q : queries) {
    for (double radius : {0.5 * cell, cell, 2.5 * cell}) {
      std::vector<uint32_t> found;
      grid.ForEachWithin(q, radius, [&](uint32_t i, double d2) {
        EXPECT_NEAR(d2, (points[i] - q).cast<double>().squaredNorm(), 1e-9);
        found.push_back(i);
      });
      std::sort(found.begin(), found.end());
      const std::vector<uint32_t> expected = BruteForceWithin(points, q, radius);
      EXPECT_EQ(found, expected) << "radius " << radius;
      std::vector<uint32_t> slots;
      grid.ForEachSlotWithin(q, radius, [&](uint32_t slot, double) {
        EXPECT_EQ(grid.slot_positions()[slot], points[grid.order()[slot]]);
        slots.push_back(grid.order()[slot]);
      });
      std::sort(slots.begin(), slots.end());
      EXPECT_EQ(slots, expected);
      EXPECT_EQ(grid.AnyWithin(q, radius, [](uint32_t, double) { return true; }),
                !expected.empty());
      double d2 = 0;
      const int64_t nearest = grid.Nearest(q, radius, &d2);
      if (expected.empty()) {
        EXPECT_EQ(nearest, -1);
      } else {
        ASSERT_GE(nearest, 0);
        double best = 1e300;
        for (uint32_t i : expected)
          best = std::min(best, (points[i] - q).cast<double>().squaredNorm());
        EXPECT_DOUBLE_EQ(d2, best);
      }
    }
  }
}

std::vector<Eigen::Vector3f> Queries(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> queries;
  for (size_t i = 0; i < points.size(); i += 97) queries.push_back(points[i]);
  queries.push_back(points[0] + Eigen::Vector3f(500, 0, 0));  // far outside every cell
  queries.push_back(points[0] + Eigen::Vector3f(-12, 3, 40));
  return queries;
}

TEST(PointGrid, CompactCloudQueriesMatchBruteForce) {
  // 8000 points in a 20 mm cube: its cells are few, stored as an array.
  const std::vector<Eigen::Vector3f> points = Clusters({{-3, 7, 100}}, 8000, 1);
  ExpectQueriesMatchBruteForce(points, 1.5, Queries(points));
}

TEST(PointGrid, ScatteredCloudQueriesMatchBruteForce) {
  // Clusters kilometres apart: the box of cells is far too big for an
  // array, so the cells are hashed, negative coordinates included.
  const std::vector<Eigen::Vector3f> points =
      Clusters({{0, 0, 0}, {-9e5f, 4e5f, 1e5f}, {7e5f, -8e5f, -3e5f}}, 1500, 2);
  ExpectQueriesMatchBruteForce(points, 2.0, Queries(points));
}

TEST(PointGrid, AFarPointDoesNotStopTheGrid) {
  // One point 10^12 mm away: the box of cells spans 10^12 cells, which the
  // grid must neither allocate nor overflow on.
  std::vector<Eigen::Vector3f> points = Clusters({{0, 0, 0}}, 500, 3);
  points.emplace_back(1e12f, -1e12f, 5);
  ExpectQueriesMatchBruteForce(points, 1.0, Queries(points));
}

TEST(PointGrid, AnEmptyGridFindsNothing) {
  const std::vector<Eigen::Vector3f> none;
  const PointGrid grid(none, 1.0);
  int visited = 0;
  grid.ForEachWithin({0, 0, 0}, 5.0, [&](uint32_t, double) { ++visited; });
  EXPECT_EQ(visited, 0);
  EXPECT_EQ(grid.Nearest({0, 0, 0}, 5.0), -1);
}

}  // namespace
}  // namespace hairrig
