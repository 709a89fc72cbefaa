#include "reconstruction/strand_direction.h"

#include <gtest/gtest.h>

#include <random>

#include "core/head_spec.h"
#include "reconstruction/polyline_overlap.h"
#include "tests/support/ellipsoid_head.h"

namespace hairrig {
namespace {

// Points from `from` towards `to`, about 2 mm apart, both ends included.
std::vector<Eigen::Vector3f> Line(const Eigen::Vector3f& from, const Eigen::Vector3f& to) {
  const int steps = std::max(2, static_cast<int>(std::ceil((to - from).norm() / 2.0f)));
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k <= steps; ++k)
    points.push_back(from + (to - from) * (static_cast<float>(k) / static_cast<float>(steps)));
  return points;
}

// Reverses a random half of the segments, as segment growing leaves them.
void ShuffleOrders(std::vector<StrandSegment>* segments, uint32_t seed) {
  std::mt19937 rng(seed);
  for (StrandSegment& s : *segments) {
    if (rng() % 2) std::reverse(s.points_mm.begin(), s.points_mm.end());
  }
}

// One strand in the plane y = const, root first: it falls from z = 100 to 0,
// turns through a half circle (ending a little lower than it began) and rises
// again to z = 40, in three segments with 3 mm gaps.
std::vector<StrandSegment> CurlThatRises(float y) {
  std::vector<StrandSegment> segments;
  segments.push_back({Line({0, y, 100}, {0, y, 0})});
  StrandSegment turn;
  for (int k = 0; k <= 16; ++k) {
    const float a = static_cast<float>(M_PI) * static_cast<float>(k) /
                    16.0f;  // from straight down to straight up
    turn.points_mm.emplace_back(10.0f - 10.0f * std::cos(a), y,
                                -3.0f - 10.0f * std::sin(a) - 0.05f * static_cast<float>(k));
  }
  segments.push_back(turn);
  segments.push_back({Line({20, y, -1}, {20, y, 40})});
  return segments;
}

TEST(StrandDirection, HangingStrandsRunRootToTipWhateverOrderTheyArriveIn) {
  // 20 strands side by side (1.5 mm apart), each cut in 4 pieces with 3 mm gaps, hanging
  // from z = 100 down a slight slope; their roots are the top ends.
  std::vector<StrandSegment> segments;
  for (int strand = 0; strand < 20; ++strand) {
    const float x = 1.5f * static_cast<float>(strand);
    for (int piece = 0; piece < 4; ++piece) {
      const float top = 100.0f - 40.0f * static_cast<float>(piece);
      segments.push_back({Line({x, 0.2f * top, top}, {x, 0.2f * (top - 37), top - 37})});
    }
  }
  ShuffleOrders(&segments, 5);
  const DirectionSummary summary = DirectSegments(&segments, nullptr, DirectionOptions{});
  EXPECT_EQ(summary.segments, 80);
  EXPECT_GT(summary.links, 0);
  EXPECT_GT(summary.overlaps, 0);
  for (size_t i = 0; i < segments.size(); ++i) {
    EXPECT_GT(segments[i].points_mm.front().z(), segments[i].points_mm.back().z())
        << "segment " << i;
  }
}

TEST(StrandDirection, LinksCarryTheRootToTipSignThroughACurlThatRises) {
  // The rising piece of CurlThatRises on its own looks like a strand falling
  // from z = 40 (its E_ribb says reverse); its links through the turn must
  // overrule that.
  std::vector<StrandSegment> expected = CurlThatRises(0);
  for (uint32_t seed = 0; seed < 8; ++seed) {
    std::vector<StrandSegment> shuffled = expected;
    ShuffleOrders(&shuffled, seed);
    const DirectionSummary summary = DirectSegments(&shuffled, nullptr, DirectionOptions{});
    EXPECT_EQ(summary.links, 2) << "seed " << seed;
    EXPECT_EQ(summary.unary_disagreements, 1)
        << "the rising piece goes against its own E_ribb, seed " << seed;
    for (size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(shuffled[i].points_mm.front(), expected[i].points_mm.front())
          << "segment " << i << " seed " << seed;
    }
  }
  // Without links, the rising piece follows its own E_ribb: the test above can fail.
  DirectionOptions unlinked;
  unlinked.alpha_link = 0;
  std::vector<StrandSegment> alone = expected;
  DirectSegments(&alone, nullptr, unlinked);
  EXPECT_EQ(alone[2].points_mm.front(), expected[2].points_mm.back());
}

TEST(StrandDirection, LinksCarryTheSignThroughABundleOfCurlsThatRise) {
  // Five such curls side by side, 1 mm apart: each end links to several
  // across each gap, and those links share one link's weight. Together with
  // the overlaps along the bundle they still overrule the rising pieces' E_ribb.
  std::vector<StrandSegment> expected;
  for (int strand = 0; strand < 5; ++strand) {
    const std::vector<StrandSegment> curl = CurlThatRises(static_cast<float>(strand));
    expected.insert(expected.end(), curl.begin(), curl.end());
  }
  for (uint32_t seed = 0; seed < 4; ++seed) {
    std::vector<StrandSegment> shuffled = expected;
    ShuffleOrders(&shuffled, seed);
    const DirectionSummary summary = DirectSegments(&shuffled, nullptr, DirectionOptions{});
    EXPECT_GT(summary.links, 10) << "seed " << seed;
    for (size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(shuffled[i].points_mm.front(), expected[i].points_mm.front())
          << "segment " << i << " seed " << seed;
    }
  }
}

TEST(StrandDirection, TheScalpDistanceDirectsHairThatLeavesTheHeadSideways) {
  // Level segments radiate from the side of an ellipsoid head: height says
  // nothing, the distance to the scalp (zeta of Eq. 5) puts the root at the head.
  const HeadSpec spec = hairrig_test::EllipsoidHeadWithWideScalp();
  auto head = HeadModel::Build(spec);
  ASSERT_TRUE(head.ok()) << head.status().ToString();
  std::vector<StrandSegment> segments;
  for (int k = 0; k < 12; ++k) {
    const float a = static_cast<float>(2 * M_PI * k / 12.0);
    const Eigen::Vector3f out(std::cos(a), std::sin(a), 0.0f), centre(0, 0, 250);
    segments.push_back({Line(centre + 85.0f * out, centre + 140.0f * out)});
  }
  std::vector<StrandSegment> expected = segments;
  ShuffleOrders(&segments, 3);
  DirectSegments(&segments, head->get(), DirectionOptions{});
  for (size_t i = 0; i < segments.size(); ++i) {
    EXPECT_EQ(segments[i].points_mm.front(), expected[i].points_mm.front()) << "segment " << i;
  }
}

TEST(StrandDirection, RootsThatMeetAtAWhorlDoNotPullEachOtherRound) {
  // Two bundles of 10 strands leave a whorl at (0, 0, 100) level and in
  // opposite directions, then fall 140 mm: their roots meet 4 mm apart, end
  // facing end, as if each strand ran on into the other side. Every root end
  // links to the 10 across the whorl; those 100 links all say "reverse one
  // bundle". Shared among an end's links they weigh as 10 links, less than
  // the 14 that reversing a bundle costs in E_ribb; counted whole they weigh
  // 100 and reverse it.
  std::vector<StrandSegment> segments;
  for (float side : {1.0f, -1.0f}) {
    for (int k = 0; k < 10; ++k) {
      const float x = 0.2f * static_cast<float>(k);
      std::vector<Eigen::Vector3f> level = Line({x, 2 * side, 100}, {x, 30 * side, 100});
      const std::vector<Eigen::Vector3f> fall = Line({x, 32 * side, 98}, {x, 60 * side, -40});
      level.insert(level.end(), fall.begin(), fall.end());
      segments.push_back({level});
    }
  }
  const std::vector<StrandSegment> expected = segments;
  ShuffleOrders(&segments, 7);
  std::vector<StrandSegment> unshared = segments;
  const DirectionSummary summary = DirectSegments(&segments, nullptr, DirectionOptions{});
  EXPECT_EQ(summary.links, 100);
  for (size_t i = 0; i < segments.size(); ++i) {
    EXPECT_EQ(segments[i].points_mm.front(), expected[i].points_mm.front()) << "segment " << i;
  }
  DirectionOptions whole_links;
  whole_links.share_link_ends = false;
  DirectSegments(&unshared, nullptr, whole_links);
  int reversed = 0;
  for (size_t i = 0; i < unshared.size(); ++i)
    reversed += unshared[i].points_mm.front() != expected[i].points_mm.front();
  EXPECT_EQ(reversed, 10) << "counted whole, the links reverse one bundle";
}

TEST(StrandDirection, ALayerOfHairDoesNotOutvoteAStrandThatCrossesIt) {
  // A layer of 100 parallel segments falling down-left (1 mm apart, each
  // overlapping its 6 nearest) and, 1 mm in front of it, one long strand
  // falling down-right across the layer. At 106 deg to the layer its tangent
  // opposes every segment it crosses, so each of those overlaps (about 60) says
  // "reverse one of the two". Counted whole they outweigh the strand's E_ribb
  // (it falls 180 mm) and reverse it; shared, the crossing overlaps weigh
  // about a sixth as much (each layer segment's summed share is about 6) and
  // the strand keeps its root first.
  const Eigen::Vector3f centre(0, 0, 500);
  const Eigen::Vector3f layer_down(-0.8f, 0, -0.6f), across_layer(0.6f, 0, -0.8f);
  const Eigen::Vector3f strand_down(0.8f, 0, -0.6f), in_front(0, 1, 0);
  std::vector<StrandSegment> segments;
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3f middle = centre + (static_cast<float>(k) - 50.0f) * across_layer;
    segments.push_back({Line(middle - 50.0f * layer_down, middle + 50.0f * layer_down)});
  }
  segments.push_back(
      {Line(centre + in_front - 150.0f * strand_down, centre + in_front + 150.0f * strand_down)});
  const std::vector<StrandSegment> expected = segments;
  ShuffleOrders(&segments, 11);
  std::vector<StrandSegment> unshared = segments;
  const DirectionSummary summary = DirectSegments(&segments, nullptr, DirectionOptions{});
  EXPECT_GT(summary.overlaps, 300) << "the layer's own overlaps and the strand's crossings";
  for (size_t i = 0; i < segments.size(); ++i) {
    EXPECT_EQ(segments[i].points_mm.front(), expected[i].points_mm.front()) << "segment " << i;
  }
  DirectionOptions whole_overlaps;
  whole_overlaps.share_overlaps = false;
  DirectSegments(&unshared, nullptr, whole_overlaps);
  EXPECT_NE(unshared.back().points_mm.front(), expected.back().points_mm.front())
      << "counted whole, the layer's overlaps reverse the strand that crosses it";
}

TEST(StrandDirection, EachSegmentKeepsItsStrongestOverlaps) {
  // 60 hanging segments 0.05 mm apart: every one overlaps every other
  // (1770 pairs). Kept to 4 each, at most 60 x 4 pairs stay, at least
  // 60 x 4 / 2, and they still direct the sheet.
  std::vector<StrandSegment> segments;
  for (int k = 0; k < 60; ++k) {
    const float x = 0.05f * static_cast<float>(k);
    segments.push_back({Line({x, 0, 100}, {x, 10, 20})});
  }
  const std::vector<StrandSegment> expected = segments;
  ShuffleOrders(&segments, 3);
  std::vector<StrandSegment> all = segments;
  DirectionOptions strongest;
  strongest.max_overlaps = 4;
  const DirectionSummary kept = DirectSegments(&segments, nullptr, strongest);
  EXPECT_EQ(kept.overlaps_found, 1770);
  EXPECT_LE(kept.overlaps, 240);
  EXPECT_GE(kept.overlaps, 120);
  for (size_t i = 0; i < segments.size(); ++i)
    EXPECT_EQ(segments[i].points_mm.front(), expected[i].points_mm.front()) << "segment " << i;
  DirectionOptions every;
  every.max_overlaps = 0;
  const DirectionSummary whole = DirectSegments(&all, nullptr, every);
  EXPECT_EQ(whole.overlaps, 1770);
  EXPECT_EQ(whole.overlaps_found, 1770);
}

TEST(KeepStrongestOverlaps, EachOwnerKeepsItsLargestSharesAndAPairStaysIfEitherKeepsIt) {
  // Owner 0 overlaps 1..5 with shares 0.1..0.5; owner 1 also overlaps 2 and
  // 3 more strongly than it does 0. Keeping 2 each: 0 keeps (0,5) and (0,4);
  // 1 keeps (1,2) and (1,3); 2 to 5 keep everything they have (at most 2).
  std::vector<OwnerOverlap> overlaps;
  for (uint32_t k = 1; k <= 5; ++k) overlaps.push_back({0, k, 1, 1, 0.1 * k});
  overlaps.push_back({1, 2, 1, 1, 0.8});
  overlaps.push_back({1, 3, 1, 1, 0.7});
  overlaps.push_back({4, 5, 1, 1, 0.05});
  KeepStrongestOverlaps(6, 2, &overlaps);
  std::vector<std::pair<uint32_t, uint32_t>> kept;
  for (const OwnerOverlap& o : overlaps) kept.emplace_back(o.a, o.b);
  // (0,1) goes: neither 0 (0.1 is its weakest) nor 1 (0.8, 0.7 beat it)
  // keeps it. (0,2), (0,3) stay through 2 and 3, (4,5) through both.
  const std::vector<std::pair<uint32_t, uint32_t>> expected = {{0, 2}, {0, 3}, {0, 4}, {0, 5},
                                                               {1, 2}, {1, 3}, {4, 5}};
  EXPECT_EQ(kept, expected);
}

TEST(StrandDirection, OptionsRefuseANegativeOverlapLimit) {
  DirectionOptions options;
  options.max_overlaps = -1;
  EXPECT_FALSE(options.Check().ok());
}

}  // namespace
}  // namespace hairrig
