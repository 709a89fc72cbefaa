#include "reconstruction/curl_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "reconstruction/helix_guide.h"

namespace hairrig {
namespace {

// A point of a helix hanging down -z from `top` (mm): radius r, pitch P,
// handedness h (right-handed: anticlockwise seen from its tip below, as it
// runs down), at arc length s from the start at phase `phase`.
Eigen::Vector3f HelixPoint(const Eigen::Vector3f& top, double r, double pitch, int h, double phase,
                           double s) {
  const double c = pitch / (2 * M_PI), l = std::hypot(r, c), t = s / l;
  // Down -z, a right-handed turn about -z is clockwise seen from above.
  const double angle = phase - h * t;
  return top + Eigen::Vector3d(r * std::cos(angle), r * std::sin(angle), -c * t).cast<float>();
}

StrandSegment HelixSegment(const Eigen::Vector3f& top, double r, double pitch, int h, double phase,
                           double from_mm, double length_mm) {
  StrandSegment segment;
  for (double s = from_mm; s <= from_mm + length_mm; s += 1.0)
    segment.points_mm.push_back(HelixPoint(top, r, pitch, h, phase, s));
  return segment;
}

// The distance from p to the helix's axis line, less the radius.
double OffHelixMm(const Eigen::Vector3f& p, const Eigen::Vector3f& top, double r) {
  return std::abs(std::hypot(p.x() - top.x(), p.y() - top.y()) - r);
}

TEST(HelixGuide, WindsOnTheHelixItStartsOn) {
  for (const int h : {1, -1}) {
    const Eigen::Vector3f top(0, 0, 0);
    const double r = 6, pitch = 20, step = 1.0;
    const Curl curl{r, pitch, h};
    HelixGuide guide(step);
    Eigen::Vector3f p = HelixPoint(top, r, pitch, h, 0.3, 0);
    const Eigen::Vector3f tangent = (HelixPoint(top, r, pitch, h, 0.3, 0.01) - p).normalized();
    guide.Start(p, tangent, -Eigen::Vector3f::UnitZ(), curl);
    double worst = 0, worst_from_truth = 0;
    const double turn = std::hypot(2 * M_PI * r, pitch);
    for (double s = step; s < 3 * turn; s += step) {
      p += guide.Next(p, -Eigen::Vector3f::UnitZ()) * static_cast<float>(step);
      worst = std::max(worst, OffHelixMm(p, top, r));
      // The same point of the true helix: the turn's sense and rate held.
      worst_from_truth = std::max(
          worst_from_truth, static_cast<double>((p - HelixPoint(top, r, pitch, h, 0.3, s)).norm()));
    }
    EXPECT_LT(worst, 0.1) << "handedness " << h;
    EXPECT_LT(worst_from_truth, 0.5) << "handedness " << h;
    // Three turns down: the pitch held.
    EXPECT_NEAR(-p.z(), 3 * pitch, 0.5) << "handedness " << h;
  }
}

// Started on the bend of the stretch a strand followed (its tangent and the
// side it turns to over the last 4 mm, as growth measures them), the guide
// winds on the ringlet's own helix about its own axis, with no axis given;
// started about the seen strand's own direction (the field at the seen
// surface) it kinks off at once.
TEST(HelixGuide, StartedOnABendWindsOnItsRingletWithNoAxisGiven) {
  for (const int h : {1, -1}) {
    const Eigen::Vector3f top(0, 0, 0);
    const double r = 6, pitch = 20, step = 1.0, at = 30;
    const Curl curl{r, pitch, h};
    const auto tangent = [&](double s) {
      return (HelixPoint(top, r, pitch, h, 0.3, s + 0.5) -
              HelixPoint(top, r, pitch, h, 0.3, s - 0.5))
          .normalized()
          .eval();
    };
    const Eigen::Vector3f t = tangent(at), earlier = tangent(at - 4);
    HelixGuide on_bend(step), about_tangent(step);
    Eigen::Vector3f p = HelixPoint(top, r, pitch, h, 0.3, at), q = p;
    on_bend.StartOnBend(p, t, (t + earlier).normalized(), (t - earlier).normalized(), curl);
    about_tangent.Start(q, t, t, curl);
    EXPECT_LT((on_bend.axis() + Eigen::Vector3f::UnitZ()).norm(), 0.05) << "handedness " << h;
    const Eigen::Vector3d centre = on_bend.centre();
    EXPECT_LT(std::hypot(centre.x() - top.x(), centre.y() - top.y()), 0.1) << "handedness " << h;
    double worst = 0;
    for (double s = at + step; s < at + std::hypot(2 * M_PI * r, pitch); s += step) {
      p += on_bend.Next(p, on_bend.axis()) * static_cast<float>(step);
      worst =
          std::max(worst, static_cast<double>((p - HelixPoint(top, r, pitch, h, 0.3, s)).norm()));
    }
    EXPECT_LT(worst, 0.5) << "handedness " << h;
    const Eigen::Vector3f kinked = about_tangent.Next(q, t);
    EXPECT_GT(std::acos(std::clamp(kinked.dot(t), -1.f, 1.f)) * 180 / M_PI, 40)
        << "handedness " << h;
  }
}

TEST(HelixGuide, DrawsAStrayStrandBack) {
  const Curl curl{6, 20, 1};
  HelixGuide guide(1.0);
  const Eigen::Vector3f axis = -Eigen::Vector3f::UnitZ();
  Eigen::Vector3f p(6, 0, 0);
  guide.Start(p, Eigen::Vector3f(0, -1, -1).normalized(), axis, curl);
  p.x() += 1.5f;  // pushed out (as the head's clearance does)
  for (int k = 0; k < 20; ++k) p += guide.Next(p, axis);
  const Eigen::Vector3d centre = guide.centre();
  EXPECT_NEAR(std::hypot(p.x() - centre.x(), p.y() - centre.y()), 6.0, 0.3);
}

// Moving the centre away from the point the strand heads for moves that
// point as far, square to the axis, and the helix keeps winding about the
// moved centre.
TEST(HelixGuide, MovesItsCentreAwayFromAPointItMustNotReach) {
  const Curl curl{6, 20, 1};
  HelixGuide guide(1.0);
  const Eigen::Vector3f axis = -Eigen::Vector3f::UnitZ();
  const Eigen::Vector3f p(6, 0, 0);
  guide.Start(p, Eigen::Vector3f(0, -1, -1).normalized(), axis, curl);
  const Eigen::Vector3f q = p + guide.Next(p, axis);
  const Eigen::Vector3d before = guide.centre();
  EXPECT_TRUE(guide.MoveCentreAwayFrom(q, 2.0));
  const Eigen::Vector3d moved = guide.centre() - before;
  EXPECT_NEAR(moved.norm(), 2.0, 1e-9);
  EXPECT_NEAR(moved.z(), 0.0, 1e-9) << "square to the axis";
  // Along the centre's offset from q, square to the axis (the axis is -z).
  Eigen::Vector3d from_q = before - q.cast<double>();
  from_q.z() = 0;
  EXPECT_NEAR(moved.normalized().dot(from_q.normalized()), 1.0, 1e-9) << "away from q";
  // The point it now heads for lies 2 mm further from q, square to the axis.
  const Eigen::Vector3f towards = guide.Towards(p);
  EXPECT_NEAR(towards.norm(), 1.0f, 1e-5f);
  Eigen::Vector3f r = p;
  for (int k = 0; k < 40; ++k) r += guide.Next(r, axis);
  EXPECT_NEAR(std::hypot(r.x() - guide.centre().x(), r.y() - guide.centre().y()), 6.0, 0.3);
  // A point on the axis gives no side to move to.
  const Eigen::Vector3d still = guide.centre();
  EXPECT_FALSE(guide.MoveCentreAwayFrom(still.cast<float>(), 2.0));
  EXPECT_LT((guide.centre() - still).norm(), 1e-9);
}

// Ringlets on an 8 mm grid (closer than their 12 mm width, as ringlets hang
// on a head), each seen as a few arcs of about two thirds of a turn; arc
// `arc` of ringlet k (in column k / 12) winds handedness(k, arc).
std::vector<StrandSegment> Ringlets(double r, double pitch,
                                    const std::function<int(int, int)>& handedness) {
  std::vector<StrandSegment> segments;
  int k = 0;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 12; ++j, ++k) {
      const Eigen::Vector3f top(8.0f * static_cast<float>(i), 8.0f * static_cast<float>(j), 0);
      const double phase = 0.7 * k;
      for (int arc = 0; arc < 3; ++arc) {
        const double from = 40.0 * arc;
        segments.push_back(HelixSegment(top, r, pitch, handedness(k, arc), phase, from, 24));
        // One ringlet in eight seen the wrong way along (its segments run up):
        // a helix winds the same way whichever way it is run along.
        if (k % 8 == 0)
          std::reverse(segments.back().points_mm.begin(), segments.back().points_mm.end());
      }
    }
  }
  return segments;
}

std::vector<StrandSegment> Ringlets(double r, double pitch, int h) {
  return Ringlets(r, pitch, [h](int, int) { return h; });
}

TEST(CurlField, EstimatesTheRingletsCurl) {
  for (const int h : {1, -1}) {
    const CurlField field = CurlField::Estimate(Ringlets(6, 20, h), CurlFieldOptions{});
    const CurlEstimate& e = field.estimate();
    ASSERT_TRUE(e.curl.curly()) << "handedness " << h;
    EXPECT_EQ(e.curl.handedness, h);
    EXPECT_NEAR(e.curl.radius_mm, 6, 1.2);
    EXPECT_NEAR(e.curl.pitch_mm, 20, 4);
    EXPECT_GT(e.HandednessAgreement(), 0.9);
    // Wherever strands grow, by default; near the seen arcs only, with kNearArcs.
    EXPECT_NE(field.At(Eigen::Vector3f(50, 50, -60)), nullptr);
    EXPECT_NE(field.At(Eigen::Vector3f(50, 50, -400)), nullptr);
    CurlFieldOptions near_arcs;
    near_arcs.region = CurlRegion::kNearArcs;
    const CurlField near_field = CurlField::Estimate(Ringlets(6, 20, h), near_arcs);
    EXPECT_NE(near_field.At(Eigen::Vector3f(50, 50, -60)), nullptr);
    EXPECT_EQ(near_field.At(Eigen::Vector3f(50, 50, -400)), nullptr);
    EXPECT_EQ(field.estimate().region, CurlRegion::kWholeHair);
    EXPECT_EQ(near_field.estimate().region, CurlRegion::kNearArcs);
  }
}

// Curly by the test, but with fewer arcs than winding everywhere asks for:
// the strands wind near the arcs only.
TEST(CurlField, FewArcsWindOnlyNearThemselves) {
  std::vector<StrandSegment> segments = Ringlets(6, 20, 1);
  // Straight seen strands far from the ringlets, as many as they are.
  const size_t ringlets = segments.size();
  for (size_t k = 0; k < ringlets; ++k) {
    StrandSegment straight;
    for (const Eigen::Vector3f& p : segments[k].points_mm)
      straight.points_mm.push_back(Eigen::Vector3f(400 + 2.0f * static_cast<float>(k), 0, p.z()));
    segments.push_back(straight);
  }
  CurlFieldOptions options;
  options.whole_hair_min_arc_share = 0.9;
  const CurlField field = CurlField::Estimate(segments, options);
  ASSERT_TRUE(field.estimate().curl.curly());
  ASSERT_LT(field.estimate().arc_share, 0.9);
  EXPECT_EQ(field.estimate().region, CurlRegion::kNearArcs);
  EXPECT_NE(field.At(Eigen::Vector3f(50, 50, -60)), nullptr);
  EXPECT_EQ(field.At(Eigen::Vector3f(50, 50, -400)), nullptr);
}

// Every value's name parses back to it; an unknown name leaves the target
// as it was.
template <typename Enum, size_t N>
void ExpectNamesParseBack(const Enum (&values)[N], const char* (*name)(Enum),
                          bool (*parse)(const std::string&, Enum*), const char* unknown) {
  for (const Enum value : values) {
    Enum parsed = value == values[0] ? values[N - 1] : values[0];
    ASSERT_TRUE(parse(name(value), &parsed)) << name(value);
    EXPECT_EQ(parsed, value);
  }
  Enum unchanged = values[N - 1];
  EXPECT_FALSE(parse(unknown, &unchanged)) << unknown;
  EXPECT_EQ(unchanged, values[N - 1]);
}

TEST(CurlRegion, NamesParseBack) {
  const CurlRegion regions[] = {CurlRegion::kNearArcs, CurlRegion::kWholeHair};
  ExpectNamesParseBack(regions, CurlRegionName, ParseCurlRegion, "everywhere");
}

TEST(CurlRadiusFrom, NamesParseBack) {
  ExpectNamesParseBack(kCurlRadiusFroms, CurlRadiusFromName, ParseCurlRadiusFrom, "torsion");
}

TEST(CurlField, EveryShapeEstimateFindsAnIdealHelix) {
  // On ideal helices the arcs turn about their axis as their curvature says,
  // so every estimate finds the curl; a looser, longer one too.
  for (const auto& [r, pitch] : {std::pair{6.0, 20.0}, std::pair{10.0, 40.0}}) {
    for (const CurlRadiusFrom from : kCurlRadiusFroms) {
      CurlFieldOptions o;
      o.radius_from = from;
      const CurlEstimate e = CurlField::Estimate(Ringlets(r, pitch, 1), o).estimate();
      ASSERT_TRUE(e.curl.curly()) << "radius " << r;
      EXPECT_EQ(e.radius_from, from) << "radius " << r;
      // The fit is exact on exact arcs; the other estimates within a fifth.
      const double tolerance = FromFittedHelices(from) ? 0.02 : 0.2;
      EXPECT_NEAR(e.curl.radius_mm, r, tolerance * r) << "radius " << r;
      EXPECT_NEAR(e.curl.pitch_mm, pitch, tolerance * pitch) << "radius " << r;
      EXPECT_NEAR(e.fitted.radius_mm, r, 0.02 * r) << "radius " << r;
      EXPECT_NEAR(e.fitted.pitch_mm, pitch, 0.02 * pitch) << "radius " << r;
      EXPECT_EQ(e.fitted_arcs, e.arcs) << "radius " << r;
      // A helix's curvature: r / (r^2 + (P / 2 pi)^2).
      const double c = pitch / (2 * M_PI);
      EXPECT_NEAR(e.curvature_per_mm, r / (r * r + c * c), 0.01) << "radius " << r;
      EXPECT_NEAR(e.torsion_per_mm, c / (r * r + c * c), 0.01) << "radius " << r;
    }
  }
}

TEST(CurlField, LooseCurlsTooShortToFitTakeTheirBending) {
  // The ringlets' 24 mm arcs turn under a quarter turn of a 15 / 40 mm
  // helix (25.6 mm), so no arc is fitted: the shape comes from the arcs'
  // curvature and torsion, and says so.
  const CurlEstimate e = CurlField::Estimate(Ringlets(15, 40, 1), CurlFieldOptions{}).estimate();
  ASSERT_TRUE(e.curl.curly());
  EXPECT_EQ(e.fitted_arcs, 0);
  EXPECT_EQ(e.radius_from, CurlRadiusFrom::kCurvatureAndTorsion);
  EXPECT_NEAR(e.curl.radius_mm, 15, 3);
}

TEST(CurlEstimate, EachShapeEstimateUsesItsOwnMeasures) {
  // Measures that no one helix has, so each estimate gives its own shape.
  CurlEstimate e;
  e.helix_angle_deg = 60;
  e.rate_per_mm = 0.1;
  e.curvature_per_mm = 0.12;
  e.torsion_per_mm = 0.05;
  const double sin_alpha = std::sin(M_PI / 3), tan_alpha = std::tan(M_PI / 3);
  e.radius_from = CurlRadiusFrom::kCurvatureAndTorsion;
  EXPECT_NEAR(e.RawShape().radius_mm, 0.12 / 0.0169, 1e-9);
  EXPECT_NEAR(e.RawShape().pitch_mm, 2 * M_PI * 0.05 / 0.0169, 1e-9);
  e.radius_from = CurlRadiusFrom::kCurvature;
  EXPECT_NEAR(e.RawShape().radius_mm, sin_alpha * sin_alpha / 0.12, 1e-9);
  EXPECT_NEAR(e.RawShape().pitch_mm, 2 * M_PI * e.RawShape().radius_mm / tan_alpha, 1e-9);
  e.radius_from = CurlRadiusFrom::kTurnRate;
  EXPECT_NEAR(e.RawShape().radius_mm, sin_alpha / 0.1, 1e-9);
  e.fitted = {5.5, 23};
  for (const CurlRadiusFrom from : {CurlRadiusFrom::kHelixFit, CurlRadiusFrom::kHelixFitLessBias}) {
    e.radius_from = from;
    EXPECT_EQ(e.RawShape().radius_mm, 5.5);
    EXPECT_EQ(e.RawShape().pitch_mm, 23);
  }
  e.fitted = {};
  EXPECT_TRUE(std::isinf(e.RawShape().radius_mm));
  e.radius_from = CurlRadiusFrom::kTurnRate;
  // Arcs that do not bend give no shape.
  e.rate_per_mm = 0;
  EXPECT_TRUE(std::isinf(e.RawShape().radius_mm));
  e.radius_from = CurlRadiusFrom::kCurvatureAndTorsion;
  e.curvature_per_mm = 0;
  EXPECT_TRUE(std::isinf(e.RawShape().radius_mm));
}

TEST(CurlField, RingletsWindEitherWayWhereTheyAreSeenToWind) {
  // The ringlets of columns 0-5 wind right-handed, those of 6-11 left.
  const CurlField field = CurlField::Estimate(
      Ringlets(6, 20, [](int k, int) { return k / 12 < 6 ? 1 : -1; }), CurlFieldOptions{});
  const CurlEstimate& e = field.estimate();
  ASSERT_TRUE(e.curl.curly());
  EXPECT_NEAR(e.right_handed_share, 0.5, 0.05);
  EXPECT_GT(e.local_handedness_agreement, 0.85);
  EXPECT_NEAR(e.curl.radius_mm, 6, 1.2);
  for (const float y : {10.0f, 50.0f, 80.0f}) {
    for (const float z : {-10.0f, -30.0f, -50.0f}) {
      const Curl* right = field.At(Eigen::Vector3f(8, y, z));
      const Curl* left = field.At(Eigen::Vector3f(80, y, z));
      ASSERT_NE(right, nullptr);
      ASSERT_NE(left, nullptr);
      EXPECT_EQ(right->handedness, 1) << "y " << y << " z " << z;
      EXPECT_EQ(left->handedness, -1) << "y " << y << " z " << z;
      EXPECT_EQ(left->radius_mm, right->radius_mm);
    }
  }
}

TEST(CurlField, WhereNoArcIsNearTheHeadsMajorityWinds) {
  // Columns 0-3 wind left-handed, 4-11 right: most of the arcs turn right.
  const CurlField field = CurlField::Estimate(
      Ringlets(6, 20, [](int k, int) { return k / 12 < 4 ? -1 : 1; }), CurlFieldOptions{});
  ASSERT_TRUE(field.estimate().curl.curly());
  EXPECT_EQ(field.estimate().curl.handedness, 1);
  const Curl* near_left = field.At(Eigen::Vector3f(8, 40, -30));
  // 19 mm beyond the left-handed ringlets (6 mm in radius about x = 0): in the
  // region, with no arc in the axis cells around it.
  const Curl* beyond_left = field.At(Eigen::Vector3f(-25, 40, -30));
  ASSERT_NE(near_left, nullptr);
  ASSERT_NE(beyond_left, nullptr);
  EXPECT_EQ(near_left->handedness, -1);
  EXPECT_EQ(beyond_left->handedness, 1);
}

TEST(CurlField, ArcsTurningEitherWayAtRandomAreNoCurl) {
  // Each arc of every ringlet winds a way of its own: stray bends, not a ringlet.
  std::mt19937 rng(5);
  std::vector<int> ways(3 * 144);
  for (int& w : ways) w = rng() % 2 ? 1 : -1;
  const CurlEstimate e =
      CurlField::Estimate(Ringlets(6, 20, [&](int k, int arc) { return ways[3 * k + arc]; }),
                          CurlFieldOptions{})
          .estimate();
  EXPECT_GT(e.arcs, 300);
  EXPECT_LT(e.local_handedness_agreement, CurlFieldOptions{}.min_handedness_agreement);
  std::printf("random arcs: %.3f of their length turning as the arcs beside them\n",
              e.local_handedness_agreement);
  EXPECT_FALSE(e.curl.curly());
}

TEST(CurlField, StraightAndWavyHairDoNotCurl) {
  std::vector<StrandSegment> straight, wavy;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 20; ++j) {
      StrandSegment s, w;
      for (int k = 0; k < 60; ++k) {
        const float x = 4.0f * static_cast<float>(i), y = 4.0f * static_cast<float>(j);
        const float z = -static_cast<float>(k);
        s.points_mm.emplace_back(x + 0.05f * static_cast<float>(k), y, z);
        // A wave in one plane: 3 mm amplitude, 30 mm period.
        w.points_mm.emplace_back(x + 3.0f * std::sin(2 * static_cast<float>(M_PI) * z / 30), y, z);
      }
      straight.push_back(std::move(s));
      wavy.push_back(std::move(w));
    }
  }
  for (const auto* segments : {&straight, &wavy}) {
    const CurlField field = CurlField::Estimate(*segments, CurlFieldOptions{});
    EXPECT_FALSE(field.estimate().curl.curly());
    EXPECT_EQ(field.At(Eigen::Vector3f(40, 40, -30)), nullptr);
  }
}

TEST(CurlField, EverywhereAndOff) {
  const CurlField given = CurlField::Everywhere(Curl{6, 20, -1});
  ASSERT_NE(given.At(Eigen::Vector3f(1e4f, 0, 0)), nullptr);
  EXPECT_EQ(given.At(Eigen::Vector3f::Zero())->handedness, -1);
  CurlFieldOptions off;
  off.enabled = false;
  EXPECT_FALSE(CurlField::Estimate(Ringlets(6, 20, 1), off).estimate().curl.curly());
}

TEST(Curl, CheckNamesWhatIsWrong) {
  EXPECT_TRUE(Curl{}.Check().ok());
  EXPECT_TRUE((Curl{6, 20, -1}.Check().ok()));
  EXPECT_NE(Curl({INFINITY, 20, 1}).Check().message().find("radius_mm"), std::string::npos);
  EXPECT_NE(Curl({6, 20, 0}).Check().message().find("handedness"), std::string::npos);
}

TEST(CurlField, OptionsNameTheirField) {
  EXPECT_TRUE(CurlFieldOptions{}.Check().ok());
  // Each case: the word the message names, and a value out of range.
  const std::vector<std::pair<std::string, void (*)(CurlFieldOptions&)>> cases = {
      {"min_arc_angle_deg", [](CurlFieldOptions& o) { o.min_arc_angle_deg = 95; }},
      {"radii", [](CurlFieldOptions& o) { o.max_radius_mm = 1; }},
      {"min_depth_mm", [](CurlFieldOptions& o) { o.min_depth_mm = -1; }},
      {"bend_span_mm", [](CurlFieldOptions& o) { o.bend_span_mm = 0; }},
      {"min_bend_deg", [](CurlFieldOptions& o) { o.min_bend_deg = 90; }},
      {"bend_axis_relax_mm", [](CurlFieldOptions& o) { o.bend_axis_relax_mm = std::nan(""); }},
      {"whole_hair_min_arc_share", [](CurlFieldOptions& o) { o.whole_hair_min_arc_share = 2; }}};
  for (const auto& [field, set_bad] : cases) {
    CurlFieldOptions o;
    set_bad(o);
    const Status status = o.Check();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << field;
  }
}

}  // namespace
}  // namespace hairrig
