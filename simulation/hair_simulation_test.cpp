#include "simulation/hair_simulation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>

#include "core/head_model.h"
#include "simulation/guide_interpolation.h"
#include "simulation/helix.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

// Guides rooted on the upper half of a head ball (centre origin, radius
// 80 mm), leaving it outward then curving down: a small hairstyle in mm, z up.
HelixModel SmallHairstyle(int guides) {
  HelixModel model;
  for (int g = 0; g < guides; ++g) {
    const double azimuth = 2 * 3.14159265358979 * g / guides;
    const Eigen::Vector3d out(std::cos(azimuth), std::sin(azimuth), 0.3);
    Eigen::Vector3d p = 81.0 * out.normalized();
    Eigen::Vector3d t = out.normalized();
    PiecewiseHelix guide;
    for (int e = 0; e < 6; ++e) {
      const Eigen::Vector3d normal =
          (Eigen::Vector3d(0, 0, -1) - t.dot(Eigen::Vector3d(0, 0, -1)) * t).normalized();
      const HelixElement h =
          HelixFromCurvatureTorsion(p, t, normal, e < 3 ? 0.02 : 0.002, 0.001, 20);
      guide.elements.push_back(h);
      p = h.PointAt(h.length_mm);
      t = h.TangentAt(h.length_mm);
    }
    model.guides.push_back(guide);
    model.guide_strands.push_back(g);
  }
  return model;
}

HairSimulationOptions WithHead() {
  HairSimulationOptions o;
  o.has_head = true;
  o.head_center_mm = Eigen::Vector3d::Zero();
  o.head_radii_mm = Eigen::Vector3d(80, 80, 80);
  return o;
}

double MaxTipMove(const std::vector<std::vector<Eigen::Vector3d>>& a,
                  const std::vector<std::vector<Eigen::Vector3d>>& b) {
  double worst = 0;
  for (size_t g = 0; g < a.size(); ++g) worst = std::max(worst, (a[g].back() - b[g].back()).norm());
  return worst;
}

TEST(HairSimulation, FittedStyleHoldsStillUnderGravity) {
  auto sim = HairSimulation::Create(SmallHairstyle(8), WithHead());
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  const auto start = (*sim)->GuideCurves(4);
  ASSERT_TRUE((*sim)->Advance(1.0).ok());
  EXPECT_LT(MaxTipMove(start, (*sim)->GuideCurves(4)), 0.5);  // mm
  EXPECT_GT((*sim)->stats().max_inverse_statics_change, 0);

  HairSimulationOptions sagging = WithHead();
  sagging.inverse_statics = false;
  auto sag = HairSimulation::Create(SmallHairstyle(8), sagging);
  ASSERT_TRUE(sag.ok());
  ASSERT_TRUE((*sag)->Advance(1.0).ok());
  EXPECT_GT(MaxTipMove(start, (*sag)->GuideCurves(4)), 5.0);
}

// The same style inside a larger head surface (radius 100 mm, a HeadModel as
// `hairrig simulate --head` gives): a fit that lies in the head.
HairSimulationOptions InsideLargerHeadSurface(bool contact_from_rest) {
  HairSimulationOptions o = WithHead();
  HeadSpec spec;
  spec.center_turntable_mm = Eigen::Vector3d::Zero();
  spec.radii_mm = Eigen::Vector3d(100, 100, 100);
  auto head = HeadModel::Build(spec);
  EXPECT_TRUE(head.ok()) << head.status().ToString();
  o.head_surface = std::move(*head);
  o.contact_from_rest = contact_from_rest;
  return o;
}

TEST(HairSimulation, ContactIsWithTheHeadSurfaceAndHeldFromRest) {
  // The guides start 81 mm from the centre, inside the 100 mm surface. Held
  // from rest: no contact and no more rest change than gravity alone needs.
  auto free = HairSimulation::Create(SmallHairstyle(8), HairSimulationOptions{});
  auto held = HairSimulation::Create(SmallHairstyle(8), InsideLargerHeadSurface(true));
  ASSERT_TRUE(free.ok() && held.ok()) << held.status().ToString();
  const auto start = (*held)->GuideCurves(4);
  ASSERT_TRUE((*held)->Advance(0.5).ok());
  EXPECT_LT(MaxTipMove(start, (*held)->GuideCurves(4)), 0.5);  // mm
  EXPECT_EQ((*held)->stats().contact_samples, 0);
  EXPECT_NEAR((*held)->stats().max_inverse_statics_change,
              (*free)->stats().max_inverse_statics_change, 1e-9);

  // With the plain margin the surface pushes on every buried sample, and the
  // rest curvatures must change far more to hold the fit against it.
  auto pushed = HairSimulation::Create(SmallHairstyle(8), InsideLargerHeadSurface(false));
  ASSERT_TRUE(pushed.ok()) << pushed.status().ToString();
  ASSERT_TRUE((*pushed)->Advance(0.5).ok());
  EXPECT_GT((*pushed)->stats().contact_samples, 0);
  EXPECT_GT((*pushed)->stats().max_inverse_statics_change,
            2 * (*free)->stats().max_inverse_statics_change);
}

TEST(HairSimulation, HeadShakeCarriesRootsAndSwingsTips) {
  HairSimulationOptions o = WithHead();
  o.scenario = Scenario::kHeadShake;
  auto sim = HairSimulation::Create(SmallHairstyle(6), o);
  ASSERT_TRUE(sim.ok());
  const auto start = (*sim)->GuideCurves(4);
  ASSERT_TRUE((*sim)->Advance(0.8).ok());
  const auto now = (*sim)->GuideCurves(4);
  const Eigen::Matrix3d turn = (*sim)->head_rotation();
  EXPECT_GT(Eigen::AngleAxisd(turn).angle(), 0.05);
  for (size_t g = 0; g < now.size(); ++g) {
    EXPECT_LT((now[g][0] - turn * start[g][0]).norm(), 1e-6) << "roots ride on the head";
  }
  // The tips lag behind the head: they are not where a rigid turn puts them.
  double lag = 0;
  for (size_t g = 0; g < now.size(); ++g)
    lag = std::max(lag, (now[g].back() - turn * start[g].back()).norm());
  EXPECT_GT(lag, 2.0);
}

TEST(HairSimulation, WindBlowsDownwind) {
  HairSimulationOptions o = WithHead();
  o.scenario = Scenario::kWind;
  o.wind_m_s = Eigen::Vector3d(3, 0, 0);
  auto sim = HairSimulation::Create(SmallHairstyle(8), o);
  ASSERT_TRUE(sim.ok());
  const auto start = (*sim)->GuideCurves(4);
  ASSERT_TRUE((*sim)->Advance(1.5).ok());
  const auto now = (*sim)->GuideCurves(4);
  double mean_dx = 0;
  for (size_t g = 0; g < now.size(); ++g)
    mean_dx += (now[g].back() - start[g].back()).x() / static_cast<double>(now.size());
  EXPECT_GT(mean_dx, 2.0);
}

TEST(HairSimulation, ThreadCountDoesNotChangeTheResult) {
  std::vector<std::vector<Eigen::Vector3d>> curves[2];
  for (int threads : {1, 2}) {
    HairSimulationOptions o = WithHead();
    o.scenario = Scenario::kHeadShake;
    o.threads = threads;
    auto sim = HairSimulation::Create(SmallHairstyle(5), o);
    ASSERT_TRUE(sim.ok());
    ASSERT_TRUE((*sim)->Advance(0.3).ok());
    curves[threads - 1] = (*sim)->GuideCurves(2);
  }
  EXPECT_EQ(MaxTipMove(curves[0], curves[1]), 0.0);
}

TEST(HairSimulation, BadInputIsNamed) {
  auto empty = HairSimulation::Create(HelixModel{}, HairSimulationOptions{});
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.status().message().find("no guide"), std::string::npos);
  HairSimulationOptions o;
  o.dynamics.time_step_s = -1;
  auto bad = HairSimulation::Create(SmallHairstyle(2), o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("time_step_s"), std::string::npos);
  EXPECT_FALSE(ParseScenario("tornado").ok());
  EXPECT_EQ(*ParseScenario("head-shake"), Scenario::kHeadShake);
}

std::vector<std::vector<Eigen::Vector3d>> Sampled(const HelixModel& model) {
  std::vector<std::vector<Eigen::Vector3d>> out;
  for (const auto& g : model.guides) out.push_back(g.Sample(5.0));
  return out;
}

TEST(GuideInterpolation, RestIsExactAndMotionFollowsGuides) {
  const HelixModel model = SmallHairstyle(8);
  const auto guides = Sampled(model);
  // Full strands: the guides themselves and strands between neighbours.
  StrandSet full;
  for (size_t g = 0; g < guides.size(); ++g) {
    std::vector<Eigen::Vector3f> own, between;
    const auto& next = guides[(g + 1) % guides.size()];
    for (size_t i = 0; i < guides[g].size(); ++i) {
      own.push_back(guides[g][i].cast<float>());
      between.push_back((0.5 * (guides[g][i] + next[std::min(i, next.size() - 1)])).cast<float>());
    }
    full.AddStrand(own);
    full.AddStrand(between);
  }
  auto interp = GuideInterpolation::Build(full, guides, GuideInterpolationOptions{});
  ASSERT_TRUE(interp.ok()) << interp.status().ToString();
  auto at_rest = interp->Apply(guides);
  ASSERT_TRUE(at_rest.ok());
  for (size_t i = 0; i < full.num_points(); ++i)
    EXPECT_EQ(at_rest->points_mm[i], full.points_mm[i]);

  // Translate every guide: every particle translates with them (weights sum to 1).
  auto moved = guides;
  for (auto& curve : moved) {
    for (auto& p : curve) p += Eigen::Vector3d(3, -2, 1);
  }
  auto shifted = interp->Apply(moved);
  ASSERT_TRUE(shifted.ok());
  for (size_t i = 0; i < full.num_points(); ++i) {
    EXPECT_LT((shifted->points_mm[i] - full.points_mm[i] - Eigen::Vector3f(3, -2, 1)).norm(), 1e-4);
  }
  // Bend one guide (and stretch it): with the plain blend the strand that is
  // that guide follows it exactly; by default it follows its direction and
  // keeps every segment's rest length.
  moved = guides;
  for (auto& p : moved[2]) p += Eigen::Vector3d(0, 0, -0.1 * (p - moved[2][0]).norm());
  GuideInterpolationOptions plain_blend;
  plain_blend.keep_lengths = false;
  auto plain = GuideInterpolation::Build(full, guides, plain_blend);
  ASSERT_TRUE(plain.ok());
  auto bent = plain->Apply(moved);
  auto bent_kept = interp->Apply(moved);
  ASSERT_TRUE(bent.ok());
  ASSERT_TRUE(bent_kept.ok());
  const auto offsets = full.Offsets();
  for (size_t i = offsets[4]; i < offsets[5]; ++i) {
    EXPECT_LT((bent->points_mm[i].cast<double>() - moved[2][i - offsets[4]]).norm(), 1e-3);
    if (i == offsets[4]) continue;
    const Eigen::Vector3f step = bent_kept->points_mm[i] - bent_kept->points_mm[i - 1];
    const Eigen::Vector3d guide_step = moved[2][i - offsets[4]] - moved[2][i - offsets[4] - 1];
    EXPECT_NEAR(step.norm(), (full.points_mm[i] - full.points_mm[i - 1]).norm(), 1e-4);
    EXPECT_GT(step.cast<double>().normalized().dot(guide_step.normalized()), 0.9999);
  }
  moved.pop_back();
  EXPECT_FALSE(interp->Apply(moved).ok());
}

// Straight guides 120 mm long hanging from z = 0, beside one another.
std::vector<std::vector<Eigen::Vector3d>> HangingGuides() {
  std::vector<std::vector<Eigen::Vector3d>> guides;
  for (int g = 0; g < 3; ++g) {
    std::vector<Eigen::Vector3d> curve;
    for (int i = 0; i <= 24; ++i) curve.push_back(Eigen::Vector3d(10.0 * g, 0, -5.0 * i));
    guides.push_back(curve);
  }
  return guides;
}

// Each guide swung about its root along +y: the displacement grows with the
// square of the arc length, 100 mm at the tip, 1 mm at 12 mm.
std::vector<std::vector<Eigen::Vector3d>> Swung(std::vector<std::vector<Eigen::Vector3d>> guides) {
  for (auto& curve : guides) {
    for (size_t i = 0; i < curve.size(); ++i) {
      const double s = 5.0 * static_cast<double>(i);
      curve[i].y() += 100.0 * (s / 120.0) * (s / 120.0);
    }
  }
  return guides;
}

StrandSet StraightStrand(int points, float spacing_mm) {
  StrandSet full;
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i < points; ++i)
    line.push_back(Eigen::Vector3f(4, 1, -spacing_mm * static_cast<float>(i)));
  full.AddStrand(line);
  return full;
}

// A strand 12 mm long beside guides 120 mm long: when the guides swing
// their tips 100 mm and barely move their first 12 mm, the short strand stays
// near its rest place and keeps its length.
TEST(GuideInterpolation, AShortStrandMovesWithItsGuidesRootsNotTheirTips) {
  const auto guides = HangingGuides();
  const StrandSet full = StraightStrand(7, 2.0f);
  const std::vector<Eigen::Vector3f>& short_strand = full.points_mm;
  auto interp = GuideInterpolation::Build(full, guides, GuideInterpolationOptions{});
  ASSERT_TRUE(interp.ok()) << interp.status().ToString();
  const auto swung = Swung(guides);
  auto moved = interp->Apply(swung);
  ASSERT_TRUE(moved.ok());
  double length = 0;
  for (size_t i = 0; i < short_strand.size(); ++i) {
    EXPECT_LT((moved->points_mm[i] - short_strand[i]).norm(), 1.5) << "vertex " << i;
    if (i > 0) length += (moved->points_mm[i] - moved->points_mm[i - 1]).norm();
  }
  EXPECT_NEAR(length, 12.0, 0.5);
}

// Guides pushed up towards their roots to 40 % of their length: the plain
// blend squashes a strand beside them, the default keeps its segments' rest
// lengths along the squashed direction (straight down, no folding back).
TEST(GuideInterpolation, AStrandSquashedByTheBlendKeepsItsLengthsWithoutFolding) {
  const auto guides = HangingGuides();
  const StrandSet full = StraightStrand(25, 5.0f);
  auto squashed = guides;
  for (auto& curve : squashed)
    for (auto& p : curve) p.z() *= 0.4;
  GuideInterpolationOptions plain_blend;
  plain_blend.keep_lengths = false;
  auto plain = GuideInterpolation::Build(full, guides, plain_blend);
  auto kept = GuideInterpolation::Build(full, guides, GuideInterpolationOptions{});
  ASSERT_TRUE(plain.ok() && kept.ok());
  auto plain_out = plain->Apply(squashed);
  auto kept_out = kept->Apply(squashed);
  ASSERT_TRUE(plain_out.ok() && kept_out.ok());
  EXPECT_NEAR(plain_out->StrandLengths()[0], 48.0, 1.0);
  for (size_t i = 1; i < full.points_mm.size(); ++i) {
    const Eigen::Vector3f step = kept_out->points_mm[i] - kept_out->points_mm[i - 1];
    EXPECT_NEAR(step.norm(), 5.0f, 1e-3f) << i;
    EXPECT_GT(step.normalized().dot(Eigen::Vector3f(0, 0, -1)), 0.999f) << i;
  }
}

// A strand twice as long as its guides follows them along its whole length:
// when the guides swing, its tail bends with them instead of translating.
TEST(GuideInterpolation, AStrandLongerThanItsGuidesBendsWithThemAllAlong) {
  const auto guides = HangingGuides();
  const StrandSet full = StraightStrand(49, 5.0f);  // 240 mm
  auto interp = GuideInterpolation::Build(full, guides, GuideInterpolationOptions{});
  ASSERT_TRUE(interp.ok()) << interp.status().ToString();
  const auto swung = Swung(guides);
  auto moved = interp->Apply(swung);
  ASSERT_TRUE(moved.ok());
  const auto& p = moved->points_mm;
  const Eigen::Vector3f tail_start = (p[26] - p[25]).normalized(),
                        tail_end = (p[48] - p[47]).normalized();
  // The guides' last half turns by 17 deg (a rigid tail would not turn at all).
  EXPECT_LT(tail_start.dot(tail_end), std::cos(0.17f)) << "the tail turns by more than 10 deg";
  EXPECT_GT(p[48].y() - 1.0f, 50.0f) << "the tip swings with the guides' tips";
  EXPECT_NEAR(moved->StrandLengths()[0], 240.0, 0.01);
}

// Every simulation options struct refuses a bad value with InvalidArgument
// naming the field; its defaults pass.
TEST(SimulationOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(GuideOptions{}.Check().ok());
  EXPECT_TRUE(GuideInterpolationOptions{}.Check().ok());
  EXPECT_TRUE(FloatingTangentsOptions{}.Check().ok());
  EXPECT_TRUE(FitOptions{}.Check().ok());
  EXPECT_TRUE(DynamicsOptions{}.Check().ok());
  EXPECT_TRUE(HairMaterial{}.Check().ok());
  EXPECT_TRUE(HairSimulationOptions{}.Check().ok());
  {
    GuideOptions o;
    o.samples = 1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "samples"));
    o = GuideOptions{};
    o.target_rms_mm = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "target_rms_mm"));
    o = GuideOptions{};
    o.kmeans_iterations = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "kmeans_iterations"));
  }
  {
    GuideInterpolationOptions o;
    o.guides_per_strand = 9;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "guides_per_strand"));
    o = GuideInterpolationOptions{};
    o.regularisation = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "regularisation"));
  }
  {
    FloatingTangentsOptions o;
    o.error_sagitta_mm = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "error_sagitta_mm"));
    o = FloatingTangentsOptions{};
    o.adaptive = false;
    o.fixed_elements = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "fixed_elements"));
  }
  {
    FitOptions o;
    o.threads = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
    o = FitOptions{};
    o.guides.samples = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "guides: samples"));
    o = FitOptions{};
    o.fitting.min_elements = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "fitting: element counts"));
  }
  {
    DynamicsOptions o;
    o.quadrature_points = 6;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "quadrature_points"));
    o = DynamicsOptions{};
    o.contact_friction = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "contact_friction"));
  }
  {
    HairSimulationOptions o;
    o.material.poisson_ratio = 0.7;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "material: hair material: poisson_ratio"));
    o = HairSimulationOptions{};
    o.dynamics.air_drag = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "dynamics: air_drag"));
    o = HairSimulationOptions{};
    o.has_head = true;
    o.head_radii_mm = Eigen::Vector3d(80, 0, 90);
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "head_radii_mm"));
    o = HairSimulationOptions{};
    o.shake_frequency_hz = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "shake_frequency_hz"));
    o = HairSimulationOptions{};
    o.threads = -2;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
  }
}

// The entry points refuse bad options before any work, naming the field.
TEST(SimulationOptions, EntryPointsCheckTheirOptions) {
  HairSimulationOptions o;
  o.wind_m_s = Eigen::Vector3d(std::nan(""), 0, 0);
  auto sim = HairSimulation::Create(SmallHairstyle(2), o);
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.status().message().find("wind_m_s"), std::string::npos) << sim.status().ToString();

  GuideInterpolationOptions interpolation;
  interpolation.guides_per_strand = 0;
  auto interp = GuideInterpolation::Build(StraightStrand(3, 5.0f), HangingGuides(), interpolation);
  ASSERT_FALSE(interp.ok());
  EXPECT_NE(interp.status().message().find("guides_per_strand"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
