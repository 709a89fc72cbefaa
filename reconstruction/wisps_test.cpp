#include "reconstruction/wisps.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/head_spec.h"

namespace hairrig {
namespace {

constexpr float kStep = 2.0f;     // along the ribbons (mm)
constexpr float kSpacing = 1.5f;  // across them

// The default ellipsoid head (centre (0, 0, 250), radii 78, 95, 115) with its
// scalp: seen from (0, 0, 330), above the hairline, a centre parting in the
// plane x = 0, the face towards -y.
std::unique_ptr<HeadModel> EllipsoidHead() {
  HeadSpec spec;
  spec.scalp.defined = true;
  auto head = HeadModel::Build(spec);
  EXPECT_TRUE(head.ok()) << head.status().ToString();
  return head.ok() ? std::move(head).value() : nullptr;
}

// A flat ribbon hanging straight down in the plane x = top.x(): isocurve j
// runs down from top + (j - W/2) spacing along y, `length` steps. Its l = 0
// is the top (the root end).
Ribbon HangingRibbon(const Eigen::Vector3f& top, int width, int length, std::vector<int> segments) {
  Ribbon r;
  for (int j = 0; j <= width; ++j) {
    std::vector<Eigen::Vector3f> isocurve;
    for (int i = 0; i <= length; ++i) {
      isocurve.push_back(
          top +
          Eigen::Vector3f(0, (static_cast<float>(j) - 0.5f * static_cast<float>(width)) * kSpacing,
                          -kStep * static_cast<float>(i)));
    }
    r.isocurves.push_back(isocurve);
  }
  r.segments = std::move(segments);
  return r;
}

// Points on the ribbon's vertices and quad centres, directed along it.
void AddPointsOn(const Ribbon& r, std::vector<OrientedPoint>* points) {
  for (int j = 0; j <= r.width(); ++j)
    for (int i = 0; i <= r.length(); ++i) {
      OrientedPoint p;
      p.position_mm = r.isocurves[j][i];
      p.direction = Eigen::Vector3f(0, 0, 1);
      p.confidence = 1;
      points->push_back(p);
      if (j < r.width() && i < r.length()) {
        p.position_mm = 0.25f * (r.isocurves[j][i] + r.isocurves[j + 1][i] + r.isocurves[j][i + 1] +
                                 r.isocurves[j + 1][i + 1]);
        points->push_back(p);
      }
    }
}

RibbonCoordinates CentreCoordinates(const Ribbon& r, int i) {
  RibbonCoordinates c;
  c.w = static_cast<float>(r.width() / 2);
  c.l = static_cast<float>(i);
  c.closest = r.center()[i];
  c.orientation = Eigen::Vector3f(0, 0, -1);
  return c;
}

// A compatible link through which strands leave `from` at its tip end and
// enter `into` at its root end (the fitted segments run along their ribbons).
RibbonLink LinkInto(int into, const std::vector<Ribbon>& ribbons, int from) {
  RibbonLink link;
  link.ribbon[0] = into, link.ribbon[1] = from;
  link.segment[0] = ribbons[into].segments[0], link.segment[1] = ribbons[from].segments[0];
  link.link_point[0] = CentreCoordinates(ribbons[into], 0);
  link.link_point[1] = CentreCoordinates(ribbons[from], ribbons[from].length());
  link.at_first_vertex[0] = true, link.at_first_vertex[1] = false;
  link.segment_along_ribbon[0] = link.segment_along_ribbon[1] = true;
  return link;
}

// Two ribbons beside the head (x = 85, the head's side at about x = 77), the
// upper from z = 330 to 270, the lower from 260 to 200, linked across the gap.
struct TwoRibbons {
  std::vector<Ribbon> ribbons;
  std::vector<RibbonLink> links;
  std::vector<OrientedPoint> points;
};
constexpr int kUpper = 0, kLower = 1;

TwoRibbons HangingPair() {
  TwoRibbons t;
  t.ribbons.push_back(HangingRibbon({85, 0, 330}, 10, 30, {0}));
  t.ribbons.push_back(HangingRibbon({85, 0, 260}, 10, 30, {1}));
  t.links.push_back(LinkInto(kLower, t.ribbons, kUpper));
  for (const Ribbon& r : t.ribbons) AddPointsOn(r, &t.points);
  return t;
}

WispOptions NoInteriorWisps() {
  WispOptions o;
  o.interior_wisps = 0;
  return o;
}

double MinimumDistanceTo(const std::vector<Eigen::Vector3f>& curve, const Eigen::Vector3f& p) {
  double best = std::numeric_limits<double>::max();
  for (const Eigen::Vector3f& v : curve) best = std::min(best, static_cast<double>((v - p).norm()));
  return best;
}

TEST(Wisps, TwoLinkedRibbonsBecomeOneWispRunningFromTheScalpToTheTip) {
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  const TwoRibbons t = HangingPair();
  WispSummary summary;
  auto wisps = BuildWisps(t.points, t.ribbons, t.links, *head, NoInteriorWisps(), &summary);
  ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
  ASSERT_EQ(wisps->size(), 1u) << "the upper ribbon's own wisp is covered by the connected one";
  const Wisp& wisp = (*wisps)[0];
  EXPECT_EQ(wisp.ribbons, (std::vector<int>{kLower, kUpper}));
  EXPECT_EQ(summary.connections, 1);
  EXPECT_EQ(summary.removed_covered, 1);
  EXPECT_EQ(wisp.width(), 10);
  const std::vector<Eigen::Vector3f>& centre = wisp.center();
  for (size_t i = 1; i < centre.size(); ++i) {
    EXPECT_LE((centre[i] - centre[i - 1]).norm(), 2 * kStep) << "gap at vertex " << i;
  }
  EXPECT_LT(std::abs(head->SignedDistance(centre.front().cast<double>(), nullptr)), 1.0)
      << "rooted on the head";
  EXPECT_LT((centre.back() - t.ribbons[kLower].center().back()).norm(), 1e-3)
      << "ends at the lower ribbon's tip";
  EXPECT_LT(MinimumDistanceTo(centre, t.ribbons[kUpper].center().front()), 1e-3)
      << "passes the upper ribbon's top";
  // The transition across the 10 mm gap has inner vertices on the straight line (the points run
  // straight down).
  int in_gap = 0;
  for (const Eigen::Vector3f& v : centre) {
    if (v.z() < 269 && v.z() > 261) {
      ++in_gap;
      EXPECT_LT(std::hypot(v.x() - 85, v.y()), 0.5) << v.transpose();
    }
  }
  EXPECT_GE(in_gap, 3);

  // Without the link, each ribbon is alone: both are removed as outliers and nothing is left.
  WispSummary unlinked;
  auto none = BuildWisps(t.points, t.ribbons, {}, *head, NoInteriorWisps(), &unlinked);
  EXPECT_FALSE(none.ok());
  EXPECT_EQ(unlinked.removed_outliers, 2);
}

TEST(Wisps, ConnectingUpMustLeadTowardsTheRoot) {
  // A link that would make the lower ribbon the upper one's predecessor:
  // followed, the wisp would climb down to the lower ribbon's top and hang
  // its whole length again below the upper ribbon's root.
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  TwoRibbons t = HangingPair();
  t.links = {LinkInto(kUpper, t.ribbons, kLower)};
  WispOptions guard = NoInteriorWisps();
  guard.keep_lone_ribbon_segments = 1;  // so the unconnected ribbons stay wisps
  WispSummary guarded, paper;
  auto kept = BuildWisps(t.points, t.ribbons, t.links, *head, guard, &guarded);
  ASSERT_TRUE(kept.ok()) << kept.status().ToString();
  EXPECT_EQ(guarded.connections, 0);
  WispOptions unconstrained = guard;
  unconstrained.min_progress_mm = -1;
  ASSERT_TRUE(BuildWisps(t.points, t.ribbons, t.links, *head, unconstrained, &paper).ok());
  EXPECT_EQ(paper.connections, 1);
}

TEST(Wisps, LoneRibbonsAreOutliersAndRibbonsInsideAnotherWispAreCovered) {
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  TwoRibbons t = HangingPair();
  t.ribbons.push_back(HangingRibbon({-85, 0, 320}, 6, 20, {2}));  // alone, on the other side
  Ribbon inside;  // isocurves 2..4 of the upper ribbon, vertices 3..12
  for (int j = 2; j <= 4; ++j) {
    const auto& source = t.ribbons[kUpper].isocurves[j];
    inside.isocurves.emplace_back(source.begin() + 3, source.begin() + 13);
  }
  inside.segments = {3, 4, 5};
  t.ribbons.push_back(inside);
  AddPointsOn(t.ribbons[2], &t.points);

  WispOptions keep_big_lone_ribbons = NoInteriorWisps();
  keep_big_lone_ribbons.keep_lone_ribbon_segments =
      3;  // the inside ribbon survives as an outlier ...
  WispSummary summary;
  auto wisps = BuildWisps(t.points, t.ribbons, t.links, *head, keep_big_lone_ribbons, &summary);
  ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
  EXPECT_EQ(summary.removed_outliers, 1);
  EXPECT_EQ(summary.removed_covered, 2)
      << "... and goes as covered, with the upper ribbon's own wisp";
  ASSERT_EQ(wisps->size(), 1u);
  EXPECT_EQ((*wisps)[0].ribbons, (std::vector<int>{kLower, kUpper}));

  WispSummary paper;
  wisps = BuildWisps(t.points, t.ribbons, t.links, *head, NoInteriorWisps(), &paper);
  ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
  EXPECT_EQ(paper.removed_outliers, 2);
  EXPECT_EQ(paper.removed_covered, 1);
  EXPECT_EQ(wisps->size(), 1u);
}

TEST(Wisps, ARibbonWithoutALinkOfItsOwnConnectsUpThroughAnOverlappingRibbonsLink) {
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  TwoRibbons t = HangingPair();
  // Beside the lower ribbon, overlapping its half y >= 0, starting as high: no link of its own.
  t.ribbons.push_back(HangingRibbon({85, 7.5f, 260}, 10, 30, {2}));
  AddPointsOn(t.ribbons[2], &t.points);
  WispSummary summary;
  auto wisps = BuildWisps(t.points, t.ribbons, t.links, *head, NoInteriorWisps(), &summary);
  ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
  EXPECT_EQ(summary.connections, 2);
  EXPECT_EQ(summary.removed_outliers, 0);
  std::vector<std::vector<int>> chains;
  for (const Wisp& wisp : *wisps) chains.push_back(wisp.ribbons);
  std::sort(chains.begin(), chains.end());
  EXPECT_EQ(chains, (std::vector<std::vector<int>>{{kLower, kUpper}, {2, kUpper}}));
  for (const Wisp& wisp : *wisps) {
    if (wisp.ribbons[0] != 2) continue;
    // Eq. 9 through the overlapping ribbon: the side ribbon's first isocurve (y = 0) continues the
    // upper ribbon's centre isocurve; the ones past y = 7.5 are clamped to its last.
    EXPECT_LT(MinimumDistanceTo(wisp.isocurves[0], t.ribbons[kUpper].center()[5]), 0.01);
    EXPECT_LT(MinimumDistanceTo(wisp.isocurves[10], t.ribbons[kUpper].isocurves[10][5]), 0.01);
  }
}

// d_s at r, computed here for the centre parting in the plane x = 0 (the
// nearest parting point lies straight above r's side of the head): the
// tangent of the great circle from the parting, in the head's tangent plane.
Eigen::Vector3f ExpectedReferenceDirection(const HeadModel& head, const Eigen::Vector3f& r) {
  const Eigen::Vector3f centre = head.ScalpCenter().cast<float>();
  const Eigen::Vector3f u = (r - centre).normalized();
  const Eigen::Vector3f parting = Eigen::Vector3f(0, u.y(), u.z()).normalized();
  const Eigen::Vector3f along = (parting.dot(u) * u - parting).normalized();
  Eigen::Vector3d outward;
  head.SignedDistance(r.cast<double>(), &outward);
  const Eigen::Vector3f n = outward.cast<float>();
  return (along - along.dot(n) * n).normalized();
}

TEST(Wisps, AWispBesideTheHeadIsAttachedToTheScalpByAnInteriorStrandOutsideTheHead) {
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  std::vector<Ribbon> ribbons = {HangingRibbon({85, 0, 330}, 10, 30, {0})};
  std::vector<OrientedPoint> points;
  AddPointsOn(ribbons[0], &points);
  WispOptions options = NoInteriorWisps();
  options.keep_lone_ribbon_segments = 1;
  for (uint64_t seed : {1u, 2u, 3u}) {
    options.seed = seed;
    auto wisps = BuildWisps(points, ribbons, {}, *head, options);
    ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
    ASSERT_EQ(wisps->size(), 1u);
    const Wisp& wisp = (*wisps)[0];
    ASSERT_TRUE(wisp.attached);
    ASSERT_GE(wisp.interior_vertices, 4);
    const std::vector<Eigen::Vector3f>& centre = wisp.center();
    const Eigen::Vector3f r = centre[0], q = ribbons[0].center()[0];
    EXPECT_LT(std::abs(head->SignedDistance(r.cast<double>(), nullptr)), 1.0) << "seed " << seed;
    EXPECT_TRUE(head->OnScalp(r.cast<double>())) << r.transpose() << ", seed " << seed;
    EXPECT_LT((centre[static_cast<size_t>(wisp.interior_vertices) - 1] - q).norm(), 1e-4)
        << "reaches R_0";
    for (int j = 0; j <= wisp.width(); ++j) {
      for (int i = 1; i < wisp.interior_vertices; ++i) {
        EXPECT_GT(head->SignedDistance(wisp.isocurves[j][i].cast<double>(), nullptr), -0.05)
            << "isocurve " << j << " vertex " << i << ", seed " << seed;
      }
    }
    // Eq. 12: d_s, or towards q when q lies higher above r's tangent plane.
    Eigen::Vector3d outward;
    head->SignedDistance(r.cast<double>(), &outward);
    const Eigen::Vector3f n = outward.cast<float>(), towards_q = (q - r).normalized();
    const Eigen::Vector3f d_s = ExpectedReferenceDirection(*head, r);
    const Eigen::Vector3f d_g = n.dot(d_s) > n.dot(towards_q) ? d_s : towards_q;
    const Eigen::Vector3f first_edge = (centre[1] - centre[0]).normalized();
    const Eigen::Vector3f second_edge = (centre[2] - centre[1]).normalized();
    EXPECT_GT(first_edge.dot(d_g), std::cos(2 * M_PI / 180)) << "seed " << seed;
    EXPECT_GT(second_edge.dot(d_g), std::cos(2 * M_PI / 180)) << "seed " << seed;
  }
}

// Distance from p to the triangles of a grid (brute force).
double DistanceToGrid(const std::vector<std::vector<Eigen::Vector3f>>& grid,
                      const Eigen::Vector3f& p) {
  const auto to_segment = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f ab = b - a;
    const float t =
        ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f) : 0.0f;
    return static_cast<double>((a + t * ab - p).norm());
  };
  const auto to_triangle = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                               const Eigen::Vector3f& c) {
    const Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.squaredNorm() > 1e-12f) {
      const Eigen::Vector3f unit = n.normalized();
      const Eigen::Vector3f x = p - unit * unit.dot(p - a);
      const bool inside = (b - a).cross(x - a).dot(n) >= 0 && (c - b).cross(x - b).dot(n) >= 0 &&
                          (a - c).cross(x - c).dot(n) >= 0;
      if (inside) return static_cast<double>(std::abs(unit.dot(p - a)));
    }
    return std::min({to_segment(a, b), to_segment(b, c), to_segment(c, a)});
  };
  double best = std::numeric_limits<double>::max();
  for (size_t j = 0; j < grid.size(); ++j)
    for (size_t i = 0; i + 1 < grid[j].size(); ++i) {
      if ((grid[j][i] - p).norm() > best + 5)
        continue;  // no point of a quad a few mm across is nearer
      if (j + 1 == grid.size()) {
        best = std::min(best, to_segment(grid[j][i], grid[j][i + 1]));
        continue;
      }
      best = std::min({best, to_triangle(grid[j][i], grid[j + 1][i], grid[j + 1][i + 1]),
                       to_triangle(grid[j][i], grid[j + 1][i + 1], grid[j][i + 1])});
    }
  return best;
}

TEST(Wisps, SynthesisedStrandsLieInTheirWispsAndStartOnTheScalp) {
  const auto head = EllipsoidHead();
  ASSERT_NE(head, nullptr);
  const TwoRibbons t = HangingPair();
  WispOptions options;
  options.interior_wisps = 3;
  WispSummary summary;
  auto wisps = BuildWisps(t.points, t.ribbons, t.links, *head, options, &summary);
  ASSERT_TRUE(wisps.ok()) << wisps.status().ToString();
  EXPECT_EQ(summary.interior, 3);
  ASSERT_EQ(wisps->size(), 4u);
  SynthesisOptions thin;  // T_thick offsets strands off the surface by design: thin enough to stay
                          // within spacing
  thin.thickness_mm = 0.5;
  const StrandSet strands = SynthesizeStrands(*wisps, 300, 7, thin);
  ASSERT_EQ(strands.num_strands(), 300u);
  ASSERT_TRUE(strands.Check().ok());
  const std::vector<size_t> offsets = strands.Offsets();
  int roots_on_scalp = 0;
  for (size_t s = 0; s < strands.num_strands(); ++s) {
    const Eigen::Vector3f& root = strands.points_mm[offsets[s]];
    EXPECT_LT(std::abs(head->SignedDistance(root.cast<double>(), nullptr)), 1.0) << "strand " << s;
    roots_on_scalp += head->OnScalp(root.cast<double>()) ? 1 : 0;
    if (s % 3 != 0)
      continue;  // every third strand, every fifth vertex: the brute-force distance is slow
    for (size_t k = offsets[s]; k < offsets[s + 1]; k += 5) {
      double nearest = std::numeric_limits<double>::max();
      for (const Wisp& wisp : *wisps)
        nearest = std::min(nearest, DistanceToGrid(wisp.isocurves, strands.points_mm[k]));
      EXPECT_LT(nearest, kSpacing) << "strand " << s << " vertex " << k - offsets[s];
    }
  }
  EXPECT_GE(roots_on_scalp, 270);

  const StrandSet again = SynthesizeStrands(*wisps, 300, 7, thin);
  EXPECT_EQ(again.points_mm, strands.points_mm);
  const StrandSet other = SynthesizeStrands(*wisps, 300, 8, thin);
  EXPECT_NE(other.points_mm, strands.points_mm);
}

TEST(Wisps, RangesFromPointsOnHalfTheWispKeepItsStrandsInThatHalf) {
  // A flat wisp in the plane x = 0: isocurve j at y = 1.5 j, 40 steps down
  // from z = 0; points on the half y <= 7.5 (w in [0, 5]).
  Wisp wisp;
  const Ribbon grid = HangingRibbon({0, 7.5f, 0}, 10, 40, {});
  wisp.isocurves = grid.isocurves;
  std::vector<OrientedPoint> points;
  for (int j = 0; j <= 10; ++j)
    for (int i = 0; i <= 80; ++i) {
      OrientedPoint p;
      p.position_mm =
          Eigen::Vector3f(0.3f, 0.75f * static_cast<float>(j), -1.0f * static_cast<float>(i));
      p.direction = Eigen::Vector3f(0, 0, -1);
      points.push_back(p);
    }
  OrientedPoint crossing;  // covers the other half but runs across the wisp
  crossing.position_mm = Eigen::Vector3f(0, 13, -30);
  crossing.direction = Eigen::Vector3f(0, 1, 0);
  points.push_back(crossing);
  std::vector<Wisp> wisps = {wisp};
  const WispOptions options;
  EXPECT_EQ(SetWispRanges(points, options, &wisps), static_cast<int64_t>(points.size()) - 1);
  const Wisp& ranged = wisps[0];
  ASSERT_EQ(ranged.range_low.size(), 41u);
  EXPECT_NEAR(ranged.range_low[10], 0, 0.1);
  EXPECT_NEAR(ranged.range_high[10], 5, 0.1);
  EXPECT_LT(ranged.range_high[40] - ranged.range_low[40], 5 * options.tip_range_share + 0.1)
      << "tapered at the tip";

  SynthesisOptions flat;
  flat.thickness_mm = 0;
  const StrandSet strands = SynthesizeStrands(wisps, 200, 3, flat);
  ASSERT_EQ(strands.num_strands(), 200u);
  float low = std::numeric_limits<float>::max(), high = -low;
  for (const Eigen::Vector3f& p : strands.points_mm)
    low = std::min(low, p.y()), high = std::max(high, p.y());
  EXPECT_GT(low, -0.2f);
  EXPECT_LT(high, 5 * kSpacing + 0.2f);
  EXPECT_GT(high, 4 * kSpacing) << "the strands fill the covered half";
}

}  // namespace
}  // namespace hairrig
