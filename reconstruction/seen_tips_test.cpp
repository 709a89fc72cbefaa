#include "reconstruction/seen_tips.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

// A straight seen strand at (x, y) from z_top down to z_bottom, 1 mm steps,
// directed downward (or upward, as the direction MRF may have turned it).
StrandSegment Vertical(float x, float y, float z_top, float z_bottom, bool upward = false) {
  StrandSegment s;
  for (float z = z_top; z >= z_bottom - 1e-3f; z -= 1) s.points_mm.emplace_back(x, y, z);
  if (upward) std::reverse(s.points_mm.begin(), s.points_mm.end());
  return s;
}

const Eigen::Vector3f kDown(0, 0, -1);

TEST(SeenTips, ATipNoSeenStrandCarriesOnFromIsKept) {
  // A lock that ends at z = 160, and one that ends at z = 150 with another
  // seen strand starting 3 mm below it.
  const std::vector<StrandSegment> segments = {Vertical(0, 0, 200, 160), Vertical(20, 0, 200, 150),
                                               Vertical(20, 0.5f, 147, 100)};
  const SeenTips tips = SeenTips::Find(segments, SeenTipOptions{});
  EXPECT_EQ(tips.examined(), 3u);
  EXPECT_EQ(tips.size(), 2u) << "the first lock's tip and the continuation's own tip";
  EXPECT_TRUE(tips.Reached({0.5f, 0, 160.8f}, kDown));
  EXPECT_FALSE(tips.Reached({20, 0, 150}, kDown)) << "continued 3 mm below";
  EXPECT_TRUE(tips.Reached({20, 0.5f, 100}, kDown));
  EXPECT_FALSE(tips.Reached({0, 0, 165}, kDown)) << "5 mm above the tip: out of reach";
  EXPECT_FALSE(tips.Reached({0, 0, 160}, -kDown)) << "a strand growing the other way";
}

TEST(SeenTips, AContinuationTurnedTheOtherWayStillCarriesOn) {
  const std::vector<StrandSegment> segments = {Vertical(0, 0, 200, 150),
                                               Vertical(0, 1, 146, 100, /*upward=*/true)};
  const SeenTips tips = SeenTips::Find(segments, SeenTipOptions{});
  EXPECT_FALSE(tips.Reached({0, 0, 150}, kDown));
}

TEST(SeenTips, SeenStrandsBesideOrAcrossTheTipDoNotCarryItOn) {
  // Beside the tip (3 mm off its line), and across it (square to it).
  StrandSegment across;
  for (float x = -10; x <= 10; x += 1) across.points_mm.emplace_back(x, 0, 155);
  const std::vector<StrandSegment> segments = {Vertical(0, 0, 200, 160), Vertical(3, 0, 200, 100),
                                               across};
  const SeenTips tips = SeenTips::Find(segments, SeenTipOptions{});
  EXPECT_TRUE(tips.Reached({0, 0, 160}, kDown));
}

TEST(SeenTips, ANeighbourThatEndsBesideTheTipDoesNotCarryItOn) {
  // The strands of one lock end a few mm apart: the neighbour has a vertex
  // 1..9 mm below the tip but ends 4 mm below it; a second lock's neighbour
  // runs 20 mm past its tip.
  const std::vector<StrandSegment> segments = {
      Vertical(0, 0, 200, 150), Vertical(0.5f, 0, 200, 146), Vertical(20, 0, 200, 150),
      Vertical(20.5f, 0, 200, 130)};
  const SeenTips tips = SeenTips::Find(segments, SeenTipOptions{});
  EXPECT_TRUE(tips.Reached({0, 0, 150}, kDown)) << "the neighbour reaches 4 mm past it, not 12";
  EXPECT_TRUE(tips.Reached({0.5f, 0, 146}, kDown)) << "the neighbour's own tip";
  EXPECT_FALSE(tips.Reached({20, 0, 150}, kDown)) << "carried on 20 mm past it";

  SeenTipOptions any_vertex;
  any_vertex.carry_on_mm = 0;
  EXPECT_FALSE(SeenTips::Find(segments, any_vertex).Reached({0, 0, 150}, kDown));
}

// Oriented points along the z axis at (x, y), every 0.5 mm from z_top down
// to z_bottom, on a 1 mm grid 3 wide across it, their direction `direction`.
std::vector<OrientedPoint> PointsAlong(float x, float y, float z_top, float z_bottom,
                                       const Eigen::Vector3f& direction = kDown) {
  std::vector<OrientedPoint> points;
  for (float z = z_top; z >= z_bottom - 1e-3f; z -= 0.5f)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        points.push_back({.position_mm = {x + dx, y + dy, z}, .direction = direction});
  return points;
}

TEST(SeenTips, ATipThePointsRunOnPastIsNotKept) {
  // A seen strand that ends at z = 150 where the hair ends, and one that
  // ends at z = 150 where the hair runs on to z = 100 unseen as a strand.
  const std::vector<StrandSegment> segments = {Vertical(0, 0, 200, 150), Vertical(20, 0, 200, 150)};
  std::vector<OrientedPoint> points = PointsAlong(0, 0, 200, 150);
  const std::vector<OrientedPoint> running_on = PointsAlong(20, 0, 200, 100);
  points.insert(points.end(), running_on.begin(), running_on.end());
  // A few stray points below the first tip, across the hair's direction.
  const std::vector<OrientedPoint> across = PointsAlong(0, 0, 146, 140, {1, 0, 0});
  points.insert(points.end(), across.begin(), across.end());

  const SeenTips tips = SeenTips::Find(segments, SeenTipOptions{}, &points);
  EXPECT_EQ(tips.size(), 1u);
  EXPECT_TRUE(tips.Reached({0, 0, 150}, kDown)) << "the points end with the seen strand";
  EXPECT_FALSE(tips.Reached({20, 0, 150}, kDown)) << "the points run on 50 mm past it";

  SeenTipOptions not_asked;
  not_asked.points_ahead_max_share = 0;
  EXPECT_EQ(SeenTips::Find(segments, not_asked, &points).size(), 2u);
  EXPECT_EQ(SeenTips::Find(segments, SeenTipOptions{}).size(), 2u) << "no points given";

  // A single point ahead, under the share of those behind, leaves the tip;
  // so do points given where none lies near the tip.
  const std::vector<OrientedPoint> sparse = {{.position_mm = {0, 0, 145}, .direction = kDown}};
  std::vector<OrientedPoint> with_one = PointsAlong(0, 0, 200, 150);
  with_one.insert(with_one.end(), sparse.begin(), sparse.end());
  EXPECT_TRUE(
      SeenTips::Find({segments[0]}, SeenTipOptions{}, &with_one).Reached({0, 0, 150}, kDown));
  const std::vector<OrientedPoint> far_away = PointsAlong(100, 0, 200, 100);
  EXPECT_TRUE(
      SeenTips::Find({segments[0]}, SeenTipOptions{}, &far_away).Reached({0, 0, 150}, kDown));
}

TEST(SeenTips, ShortSeenStrandsGiveNoTips) {
  SeenTipOptions options;
  options.min_seen_length_mm = 45;
  const SeenTips tips =
      SeenTips::Find({Vertical(0, 0, 200, 160), Vertical(20, 0, 200, 150)}, options);
  EXPECT_EQ(tips.examined(), 2u);
  EXPECT_EQ(tips.size(), 1u);
  EXPECT_FALSE(tips.Reached({0, 0, 160}, kDown)) << "40 mm long";
  EXPECT_TRUE(tips.Reached({20, 0, 150}, kDown)) << "50 mm long";
}

TEST(SeenTips, OffFindsNone) {
  SeenTipOptions options;
  options.enabled = false;
  const SeenTips tips = SeenTips::Find({Vertical(0, 0, 200, 160)}, options);
  EXPECT_EQ(tips.size(), 0u);
  EXPECT_FALSE(tips.Reached({0, 0, 160}, kDown));
  EXPECT_FALSE(SeenTips().Reached({0, 0, 160}, kDown));
}

TEST(SeenTipOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(SeenTipOptions{}.Check().ok());
  // Each case: the field named, and a value out of its range.
  const std::vector<std::pair<std::string, void (*)(SeenTipOptions&)>> cases = {
      {"ahead_max_mm", [](SeenTipOptions& o) { o.ahead_max_mm = 0.5; }},
      {"lateral_mm", [](SeenTipOptions& o) { o.lateral_mm = 0; }},
      {"max_angle_deg", [](SeenTipOptions& o) { o.max_angle_deg = 120; }},
      {"min_seen_length_mm", [](SeenTipOptions& o) { o.min_seen_length_mm = -1; }},
      {"min_strand_mm", [](SeenTipOptions& o) { o.min_strand_mm = -1; }},
      {"carry_on_mm", [](SeenTipOptions& o) { o.carry_on_mm = -1; }},
      {"points_ahead_max_share", [](SeenTipOptions& o) { o.points_ahead_max_share = 2; }},
      {"points_gap_mm", [](SeenTipOptions& o) { o.points_gap_mm = -1; }},
      {"points_window_mm", [](SeenTipOptions& o) { o.points_window_mm = 0; }},
      {"points_lateral_mm", [](SeenTipOptions& o) { o.points_lateral_mm = 0; }},
      {"points_angle_deg", [](SeenTipOptions& o) { o.points_angle_deg = 0; }},
      {"reach_mm", [](SeenTipOptions& o) { o.reach_mm = -1; }}};
  for (const auto& [field, set_bad] : cases) {
    SeenTipOptions o;
    set_bad(o);
    EXPECT_TRUE(IsInvalidNaming(o.Check(), field)) << field;
  }
}

}  // namespace
}  // namespace hairrig
