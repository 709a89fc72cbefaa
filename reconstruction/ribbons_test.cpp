#include "reconstruction/ribbons.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/head_spec.h"
#include "tests/support/ellipsoid_head.h"

namespace hairrig {
namespace {

using Curve = std::vector<Eigen::Vector3f>;

// Points from `from` to `to`, about `step` mm apart, both ends included.
Curve Line(const Eigen::Vector3f& from, const Eigen::Vector3f& to, float step = 2.0f) {
  const int steps = std::max(1, static_cast<int>(std::lround((to - from).norm() / step)));
  Curve points;
  for (int k = 0; k <= steps; ++k)
    points.push_back(from + (to - from) * (static_cast<float>(k) / static_cast<float>(steps)));
  return points;
}

// A flat sheet of parallel hair: oriented points every 0.5 mm over
// width x length (mm), and strands every 2 mm across it, the middle one
// whole, the others broken in two at varying places.
struct Sheet {
  std::vector<OrientedPoint> points;
  std::vector<StrandSegment> segments;
};

Sheet MakeSheet(const Eigen::Vector3f& origin, const Eigen::Vector3f& across,
                const Eigen::Vector3f& along, float width, float length) {
  Sheet sheet;
  for (float a = 0; a <= width + 1e-3f; a += 0.5f) {
    for (float l = 0; l <= length + 1e-3f; l += 0.5f) {
      OrientedPoint p;
      p.position_mm = origin + a * across + l * along;
      p.direction = along;
      p.confidence = 1;
      sheet.points.push_back(p);
    }
  }
  const int strands = static_cast<int>(std::lround(width / 2.0f));
  for (int k = 0; k <= strands; ++k) {
    const Eigen::Vector3f start = origin + 2.0f * static_cast<float>(k) * across;
    if (k == strands / 2) {
      sheet.segments.push_back({Line(start, start + length * along)});
      continue;
    }
    const float cut = length * (0.3f + 0.4f * static_cast<float>((k * 7) % 11) / 10.0f);
    sheet.segments.push_back({Line(start, start + cut * along)});
    sheet.segments.push_back({Line(start + (cut + 2.0f) * along, start + length * along)});
  }
  return sheet;
}

// The distance between a ribbon's outer isocurves at their middle vertex.
float Span(const Ribbon& r) {
  const size_t middle = r.isocurves[0].size() / 2;
  return (r.isocurves.front()[middle] - r.isocurves.back()[middle]).norm();
}

TEST(Ribbons, AFlatSheetOfParallelStrandsIsOneRibbonAcrossIt) {
  const Sheet sheet = MakeSheet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 40, 100);
  RibbonSummary summary;
  const std::vector<Ribbon> ribbons =
      CoverWithRibbons(sheet.points, sheet.segments, RibbonOptions{}, &summary);
  ASSERT_EQ(ribbons.size(), 1u);
  const Ribbon& r = ribbons[0];
  EXPECT_EQ(r.segments.size(), sheet.segments.size());
  EXPECT_EQ(summary.covered_segments, static_cast<int64_t>(sheet.segments.size()));
  EXPECT_EQ(summary.uncovered_segments, 0);
  EXPECT_NEAR(Span(r), 40.0f, 3.0f);
  EXPECT_EQ(r.length(), 50);  // the 100 mm seed resampled every 2 mm
  for (const auto& curve : r.isocurves) {
    ASSERT_EQ(static_cast<int>(curve.size()), r.length() + 1);
    for (const Eigen::Vector3f& v : curve) EXPECT_NEAR(v.z(), 0.0f, 0.05f);
  }
}

TEST(Ribbons, TwoSheetsAtRightAnglesAreTwoRibbons) {
  Sheet a = MakeSheet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 40, 100);
  const Sheet b = MakeSheet({45, 0, 5}, {0, 0, 1}, {0, 1, 0}, 40, 100);
  const size_t a_segments = a.segments.size();
  a.points.insert(a.points.end(), b.points.begin(), b.points.end());
  a.segments.insert(a.segments.end(), b.segments.begin(), b.segments.end());
  const std::vector<Ribbon> ribbons = CoverWithRibbons(a.points, a.segments, RibbonOptions{});
  ASSERT_EQ(ribbons.size(), 2u);
  std::set<int> all;
  for (const Ribbon& r : ribbons) {
    const bool in_a = r.segments.front() < static_cast<int>(a_segments);
    for (int s : r.segments) {
      EXPECT_EQ(s < static_cast<int>(a_segments), in_a) << "a ribbon spans both sheets";
      all.insert(s);
    }
    EXPECT_NEAR(Span(r), 40.0f, 3.0f);
  }
  EXPECT_EQ(all.size(), a.segments.size());
}

TEST(Ribbons, SegmentsGrownOnASheetShareOneRibbon) {
  Sheet sheet = MakeSheet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 30, 60);
  const std::vector<StrandSegment> grown = GrowStrandSegments(sheet.points, SegmentGrowthOptions{});
  ASSERT_GT(grown.size(), 5u);
  RibbonSummary summary;
  const std::vector<Ribbon> ribbons =
      CoverWithRibbons(sheet.points, grown, RibbonOptions{}, &summary);
  ASSERT_FALSE(ribbons.empty());
  EXPECT_GE(ribbons[0].segments.size(), grown.size() * 9 / 10);
  EXPECT_GT(Span(ribbons[0]), 25.0f);
}

TEST(Ribbons, ProjectionGivesTheGridParameters) {
  Ribbon flat;  // W = 4 isocurves 1.5 mm apart across x, L = 10 steps of 2 mm along y
  for (int j = 0; j <= 4; ++j)
    flat.isocurves.push_back(
        Line({1.5f * static_cast<float>(j), 0, 0}, {1.5f * static_cast<float>(j), 20, 0}));
  ASSERT_EQ(flat.width(), 4);
  ASSERT_EQ(flat.length(), 10);

  RibbonCoordinates c = ProjectOntoRibbon(flat, {3.0f, 7.0f, 0.8f});
  EXPECT_NEAR(c.w, 2.0f, 1e-4f);
  EXPECT_NEAR(c.l, 3.5f, 1e-4f);
  EXPECT_NEAR(c.distance_mm, 0.8f, 1e-4f);
  EXPECT_NEAR((c.closest - Eigen::Vector3f(3, 7, 0)).norm(), 0.0f, 1e-4f);
  EXPECT_NEAR(c.orientation.y(), 1.0f, 1e-4f);

  c = ProjectOntoRibbon(flat, {4.0f, 13.0f, -0.3f});
  EXPECT_NEAR(c.w, 4.0f / 1.5f, 1e-4f);
  EXPECT_NEAR(c.l, 6.5f, 1e-4f);

  c = ProjectOntoRibbon(flat, {-2.0f, 5.0f, 0.0f});  // beside the ribbon
  EXPECT_NEAR(c.w, 0.0f, 1e-4f);
  EXPECT_NEAR(c.l, 2.5f, 1e-4f);
  EXPECT_NEAR(c.distance_mm, 2.0f, 1e-4f);

  c = ProjectOntoRibbon(flat, {3.0f, 24.0f, 0.0f});  // past its end
  EXPECT_NEAR(c.l, 10.0f, 1e-4f);
  EXPECT_NEAR(c.distance_mm, 4.0f, 1e-4f);

  Ribbon polyline;  // W = 0
  polyline.isocurves.push_back(Line({0, 0, 0}, {0, 20, 0}));
  c = ProjectOntoRibbon(polyline, {1.0f, 9.0f, 0.0f});
  EXPECT_NEAR(c.w, 0.0f, 1e-4f);
  EXPECT_NEAR(c.l, 4.5f, 1e-4f);
  EXPECT_NEAR(c.distance_mm, 1.0f, 1e-4f);
}

TEST(Ribbons, OverlapOfSideBySideRibbonsAndItsDirection) {
  Ribbon a, b, far;
  a.isocurves = {Line({0, 0, 0}, {0, 40, 0}), Line({1.5f, 0, 0}, {1.5f, 40, 0})};
  b.isocurves = {Line({0.5f, 0, 0.5f}, {0.5f, 40, 0.5f}), Line({2.0f, 0, 0.5f}, {2.0f, 40, 0.5f})};
  far.isocurves = {Line({10, 0, 0}, {10, 40, 0})};
  bool compatible = false;
  EXPECT_NEAR(RibbonOverlap(a, b, 1.5, &compatible), 1.0, 1e-9);
  EXPECT_TRUE(compatible);
  for (auto& curve : b.isocurves) std::reverse(curve.begin(), curve.end());
  EXPECT_NEAR(RibbonOverlap(a, b, 1.5, &compatible), 1.0, 1e-9);
  EXPECT_FALSE(compatible);
  EXPECT_EQ(RibbonOverlap(a, far, 1.5, &compatible), 0.0);
}

// A point on the circle of `radius` about `centre` in the x-z plane at angle `deg`.
Eigen::Vector3f OnCircle(const Eigen::Vector3f& centre, float radius, float deg, float y = 0) {
  const float a = deg * static_cast<float>(M_PI) / 180.0f;
  return centre + Eigen::Vector3f(radius * std::cos(a), y, radius * std::sin(a));
}

// The arc from `from_deg` to `to_deg`, vertices about 2 mm apart.
Curve ArcPoints(const Eigen::Vector3f& centre, float radius, float from_deg, float to_deg,
                float y = 0) {
  const float arc_mm = std::abs(to_deg - from_deg) * static_cast<float>(M_PI) / 180.0f * radius;
  const int steps = std::max(2, static_cast<int>(std::lround(arc_mm / 2.0f)));
  Curve points;
  for (int k = 0; k <= steps; ++k) {
    points.push_back(OnCircle(
        centre, radius,
        from_deg + (to_deg - from_deg) * static_cast<float>(k) / static_cast<float>(steps), y));
  }
  return points;
}

// Every segment its own 1-isocurve ribbon.
std::vector<Ribbon> OneRibbonEach(const std::vector<StrandSegment>& segments) {
  std::vector<Ribbon> ribbons;
  for (size_t s = 0; s < segments.size(); ++s) {
    Ribbon r;
    r.isocurves = {segments[s].points_mm};
    r.segments = {static_cast<int>(s)};
    ribbons.push_back(r);
  }
  return ribbons;
}

TEST(Ribbons, AnArcAcrossAGapLinksTwoPiecesOfOneCircle) {
  const Eigen::Vector3f centre(5, 0, 50);
  // Two 30 deg pieces of a 40 mm circle with 15 mm of arc (21.5 deg) between them;
  // the second listed from its far end.
  const float gap_deg = 15.0f / 40.0f * 180.0f / static_cast<float>(M_PI);
  std::vector<StrandSegment> segments = {{ArcPoints(centre, 40, 0, 30)},
                                         {ArcPoints(centre, 40, 30 + gap_deg, 60 + gap_deg)}};
  std::reverse(segments[1].points_mm.begin(), segments[1].points_mm.end());
  ConnectionSummary summary;
  const std::vector<RibbonLink> links =
      ConnectRibbons(OneRibbonEach(segments), segments, ConnectionOptions{}, &summary);
  EXPECT_EQ(summary.pairs_tried, 1);
  ASSERT_EQ(links.size(), 1u);
  const RibbonLink& link = links[0];
  EXPECT_NEAR(link.radius_mm, 40.0, 0.8);
  EXPECT_LT(link.rms_mm, 0.1);
  EXPECT_EQ(link.ribbon[0], 0);
  EXPECT_EQ(link.ribbon[1], 1);
  EXPECT_FALSE(link.at_first_vertex[0]);  // the first piece's last vertex faces the gap
  EXPECT_FALSE(link.at_first_vertex[1]);  // so does the reversed second piece's
  EXPECT_TRUE(link.segment_along_ribbon[0]);
  EXPECT_TRUE(link.segment_along_ribbon[1]);
  EXPECT_NEAR(link.link_point[0].l, static_cast<float>(segments[0].points_mm.size() - 1), 1e-3f);
  EXPECT_NEAR(link.link_point[1].l, static_cast<float>(segments[1].points_mm.size() - 1), 1e-3f);
  EXPECT_LT(link.link_point[0].distance_mm, 1e-3f);
}

TEST(Ribbons, SegmentsMeetingAtRightAnglesAreNotLinked) {
  const std::vector<StrandSegment> segments = {{Line({0, -22, 0}, {0, -2, 0})},
                                               {Line({2, 0, 0}, {22, 0, 0})}};
  ConnectionSummary summary;
  const auto links =
      ConnectRibbons(OneRibbonEach(segments), segments, ConnectionOptions{}, &summary);
  // The corner's two ends, and the far end of each with the corner end of the
  // other (22 mm apart), which the gap's direction rejects.
  EXPECT_EQ(summary.pairs_tried, 3);
  EXPECT_EQ(summary.rejected_direction, 2);
  EXPECT_TRUE(links.empty());
  EXPECT_EQ(summary.rejected_rms + summary.rejected_curvature, 1);
}

TEST(Ribbons, SideBySideSegmentsAreNotLinked) {
  const std::vector<StrandSegment> segments = {{Line({0, 0, 0}, {0, 20, 0})},
                                               {Line({2, 0, 0}, {2, 20, 0})}};
  ConnectionSummary summary;
  EXPECT_TRUE(
      ConnectRibbons(OneRibbonEach(segments), segments, ConnectionOptions{}, &summary).empty());
  EXPECT_EQ(summary.pairs_tried, 4);  // top-top, bottom-bottom and the two diagonals
  EXPECT_EQ(summary.rejected_direction, 4);
  // Without the gap's direction check, criterion (d) rejects them: the arc would double back.
  ConnectionOptions no_direction;
  no_direction.min_gap_cos = -1;
  EXPECT_TRUE(ConnectRibbons(OneRibbonEach(segments), segments, no_direction, &summary).empty());
  EXPECT_EQ(summary.rejected_overlap, 4);
}

// Three ribbons of three strands each (1.5 mm apart in y) along one curl
// hanging beside an ellipsoid head: A falls from near the scalp, B turns
// through the bottom of the curl, C rises again (its own height change says
// its top is its root).
struct Curl {
  std::unique_ptr<HeadModel> head;
  std::vector<StrandSegment> segments;
  std::vector<Ribbon> ribbons;
  std::vector<Eigen::Vector3f> roots;  // per ribbon, the centre isocurve's end that is the root
};

Curl MakeCurl() {
  const HeadSpec spec = hairrig_test::EllipsoidHeadWithWideScalp();
  Curl curl;
  auto head = HeadModel::Build(spec);
  EXPECT_TRUE(head.ok()) << head.status().ToString();
  if (head.ok()) curl.head = std::move(head).value();
  const Eigen::Vector3f centre(105, 0, 160);
  const float pieces[3][2] = {{150, 235}, {240, 300}, {305, 360}};
  for (const auto& piece : pieces) {
    Ribbon r;
    for (float y : {-1.5f, 0.0f, 1.5f}) {
      r.isocurves.push_back(ArcPoints(centre, 40, piece[0], piece[1], y));
      r.segments.push_back(static_cast<int>(curl.segments.size()));
      curl.segments.push_back({r.isocurves.back()});
    }
    curl.roots.push_back(r.center().front());
    curl.ribbons.push_back(r);
  }
  // Arbitrary starting orders: ribbons A and C and two segments reversed.
  for (int r : {0, 2}) {
    for (auto& curve : curl.ribbons[static_cast<size_t>(r)].isocurves)
      std::reverse(curve.begin(), curve.end());
  }
  for (int s : {1, 4})
    std::reverse(curl.segments[static_cast<size_t>(s)].points_mm.begin(),
                 curl.segments[static_cast<size_t>(s)].points_mm.end());
  return curl;
}

TEST(Ribbons, LinksDirectACurlRootToTipThroughItsRisingPart) {
  Curl curl = MakeCurl();
  ASSERT_NE(curl.head, nullptr);
  ConnectionSummary connection;
  std::vector<RibbonLink> links =
      ConnectRibbons(curl.ribbons, curl.segments, ConnectionOptions{}, &connection);
  EXPECT_EQ(connection.links, 18) << "every strand of A with every strand of B, and of B with C";
  const RibbonDirectionSummary summary =
      DirectRibbons(&curl.ribbons, &links, curl.head.get(), RibbonDirectionOptions{});
  EXPECT_EQ(summary.reversed, 2);
  EXPECT_EQ(summary.incompatible_links, 0);
  EXPECT_EQ(links.size(), 18u);
  for (size_t r = 0; r < 3; ++r) {
    EXPECT_LT((curl.ribbons[r].center().front() - curl.roots[r]).norm(), 1e-4f) << "ribbon " << r;
  }
  for (const RibbonLink& link : links) {
    // Strands run from the lower-numbered ribbon's tip (l = L) into the next one's root (l = 0).
    const int up = link.ribbon[0] < link.ribbon[1] ? 0 : 1;
    EXPECT_NEAR(link.link_point[up].l,
                static_cast<float>(curl.ribbons[static_cast<size_t>(link.ribbon[up])].length()),
                0.01f);
    EXPECT_NEAR(link.link_point[1 - up].l, 0.0f, 0.01f);
  }

  // Without the links, the rising part follows its own height: the links above decided it.
  Curl unlinked = MakeCurl();
  links = ConnectRibbons(unlinked.ribbons, unlinked.segments, ConnectionOptions{});
  RibbonDirectionOptions no_links;
  no_links.alpha_link = 0;
  DirectRibbons(&unlinked.ribbons, &links, unlinked.head.get(), no_links);
  EXPECT_LT((unlinked.ribbons[0].center().front() - unlinked.roots[0]).norm(), 1e-4f);
  EXPECT_LT((unlinked.ribbons[2].center().back() - unlinked.roots[2]).norm(), 1e-4f);
}

}  // namespace
}  // namespace hairrig
