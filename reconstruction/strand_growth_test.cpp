#include "reconstruction/strand_growth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/head_spec.h"
#include "reconstruction/colmap_model.h"
#include "reconstruction/gaussian_mixture.h"
#include "reconstruction/point_evaluation.h"
#include "reconstruction/point_reconstruction.h"
#include "reconstruction/strand_preview.h"
#include "reconstruction/strand_reconstruction.h"
#include "tests/support/front_views_testing.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

const Eigen::Vector3d kDown(0, 0, -1);

double DegreesAboveTangentPlane(const Eigen::Vector3d& direction, const Eigen::Vector3d& normal) {
  return std::asin(std::clamp(direction.dot(normal), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST(RootDirection, NinetyDegreesIsTheNormal) {
  for (const Eigen::Vector3d& normal :
       {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.6, 0, 0.8),
        Eigen::Vector3d(0, -0.8, -0.6)}) {
    EXPECT_LT((RootDirection(normal, kDown, 90) - normal).norm(), 1e-12) << normal.transpose();
  }
}

TEST(RootDirection, OnAVerticalScalpItLeavesAtTheElevationPointingDown) {
  const Eigen::Vector3d normal(0, 1, 0);
  for (const double elevation : {15.0, 30.0, 45.0, 60.0}) {
    const Eigen::Vector3d d = RootDirection(normal, kDown, elevation);
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_NEAR(DegreesAboveTangentPlane(d, normal), elevation, 1e-9);
    EXPECT_NEAR(d.x(), 0.0, 1e-12);
    EXPECT_LT(d.z(), 0.0) << "tilted towards down along the scalp";
  }
}

TEST(RootDirection, AtTheCrownItIsTheNormal) {
  EXPECT_LT((RootDirection(Eigen::Vector3d::UnitZ(), kDown, 30) - Eigen::Vector3d::UnitZ()).norm(),
            1e-12);
}

TEST(RootDirection, UnderTheChinAndOutsideItsRangeItIsTheNormal) {
  const Eigen::Vector3d under(0, 0, -1);
  EXPECT_LT((RootDirection(under, kDown, 45) - under).norm(), 1e-12);
  const Eigen::Vector3d side(1, 0, 0);
  for (const double elevation : {0.0, -30.0, 120.0, std::nan("")})
    EXPECT_LT((RootDirection(side, kDown, elevation) - side).norm(), 1e-12) << elevation;
}

TEST(RootDirection, TiltsTowardsTheFramesOwnDown) {
  // A frame whose down is +x (a COLMAP model lying on its side).
  const Eigen::Vector3d down(1, 0, 0), normal(0, 1, 0);
  const Eigen::Vector3d d = RootDirection(normal, down, 45);
  EXPECT_NEAR(d.x(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(d.y(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(d.z(), 0.0, 1e-12);
}

TEST(RootDirection, RisesFromTheElevationTowardsTheCrown) {
  // Scalp normals from vertical (0 deg) to nearly up (80 deg), in the x-z plane.
  double previous = 0;
  for (const double tilt : {0.0, 20.0, 40.0, 60.0, 80.0}) {
    const double t = tilt * M_PI / 180.0;
    const Eigen::Vector3d normal(std::cos(t), 0, std::sin(t));
    const Eigen::Vector3d d = RootDirection(normal, kDown, 45);
    const double above = DegreesAboveTangentPlane(d, normal);
    EXPECT_GE(above, 45.0 - 1e-9) << "scalp tilted " << tilt;
    EXPECT_GT(above, previous) << "scalp tilted " << tilt;
    EXPECT_LT(d.z(), normal.z()) << "points lower than the normal";
    EXPECT_NEAR(d.y(), 0.0, 1e-12);
    previous = above;
  }
}

TEST(SampleScalpRoots, DirectionsFollowTheScalpNormalTiltedByTheElevation) {
  HeadSpec spec;
  spec.scalp.defined = true;
  auto head = HeadModel::Build(spec);
  ASSERT_TRUE(head.ok()) << head.status().ToString();
  const auto normal_roots = SampleScalpRoots(**head, 500, 7, 90, kDown);
  const auto tilted_roots = SampleScalpRoots(**head, 500, 7, 40, kDown);
  ASSERT_EQ(normal_roots.size(), 500u);
  ASSERT_EQ(tilted_roots.size(), 500u);
  for (size_t k = 0; k < normal_roots.size(); ++k) {
    const Eigen::Vector3f p = normal_roots[k].position_mm;
    EXPECT_EQ(p, tilted_roots[k].position_mm) << "the same seed gives the same roots";
    Eigen::Vector3d outward;
    const double distance = (*head)->SignedDistance(p.cast<double>(), &outward);
    EXPECT_LT(std::abs(distance), 0.5) << "root " << k;
    EXPECT_GT(normal_roots[k].direction.cast<double>().dot(outward), 0.99) << "root " << k;
    const Eigen::Vector3d tilted = tilted_roots[k].direction.cast<double>();
    EXPECT_NEAR(tilted.norm(), 1.0, 1e-5);
    EXPECT_GE(DegreesAboveTangentPlane(tilted, normal_roots[k].direction.cast<double>()), 40 - 1e-3)
        << "root " << k;
    EXPECT_LE(tilted.z(), normal_roots[k].direction.z() + 1e-6) << "root " << k;
  }
}

// A curtain of straight segments hanging from z = 200 to z = 100 in the plane
// x = 0, directed downward, 2 mm apart along y.
std::vector<StrandSegment> HangingCurtain() {
  std::vector<StrandSegment> segments;
  for (float y = -20; y <= 20; y += 2) {
    StrandSegment s;
    for (float z = 200; z >= 100; z -= 2) s.points_mm.emplace_back(0, y, z);
    segments.push_back(std::move(s));
  }
  return segments;
}

TEST(GrowStrandsInField, StrandsFollowACurtainOfDirectedSegmentsAndStopAtItsEnd) {
  const std::vector<StrandSegment> curtain = HangingCurtain();
  std::vector<DirectedRoot> roots;
  for (float y = -15; y <= 15; y += 5) roots.push_back({{0, y, 200}, {0, 0, -1}});
  const auto field = HybridOrientationField::Build(curtain, roots, nullptr, HybridFieldOptions{});
  ASSERT_TRUE(field.ok()) << field.status().ToString();
  StrandGrowthOptions options;
  StrandGrowthSummary summary;
  const StrandSet strands = GrowStrandsInField(*field, roots, nullptr, options, &summary);
  ASSERT_EQ(strands.num_strands(), roots.size());
  EXPECT_EQ(summary.stopped_volume, static_cast<int64_t>(roots.size()))
      << "every strand leaves the hair volume before the maximum length";
  const std::vector<size_t> offsets = strands.Offsets();
  for (size_t s = 0; s < strands.num_strands(); ++s) {
    const std::vector<Eigen::Vector3f> strand(strands.points_mm.begin() + offsets[s],
                                              strands.points_mm.begin() + offsets[s + 1]);
    for (size_t k = 1; k < strand.size(); ++k) {
      EXPECT_LT(std::abs(strand[k].x()), 1.0) << "strand " << s << " vertex " << k;
      EXPECT_NEAR(strand[k].y(), roots[s].position_mm.y(), 1.0)
          << "strand " << s << " vertex " << k;
      EXPECT_LT(strand[k].z(), strand[k - 1].z()) << "strand " << s << " vertex " << k;
    }
    // The curtain ends at z = 100 (measured: every strand's last vertex at 99).
    EXPECT_NEAR(strand.back().z(), 100.0, 4.0) << "strand " << s;
  }
}

// The curtain above with, 4 mm beside it, two locks that end at z = 150, in
// a hair volume that reaches far past them. A strand grown along a
// lock ends at the lock's tip with the seen tips, and runs on down the
// curtain's field without them.
TEST(FieldGrowth, AStrandFollowingASeenStrandToItsTipEndsThere) {
  std::vector<StrandSegment> hair = HangingCurtain();
  for (const float y : {24.f, 26.f}) {
    StrandSegment lock;
    for (float z = 200; z >= 150; z -= 2) lock.points_mm.emplace_back(0, y, z);
    hair.push_back(std::move(lock));
  }
  const std::vector<DirectedRoot> roots = {{{0, -10, 200}, {0, 0, -1}}, {{0, 25, 200}, {0, 0, -1}}};
  const auto field = HybridOrientationField::Build(hair, roots, nullptr, HybridFieldOptions{});
  ASSERT_TRUE(field.ok()) << field.status().ToString();
  StrandGrowthOptions options;
  options.volume_bound = 30;  // I_d stops no strand: only the seen tip (or the box) ends it
  const auto lowest_z = [](const StrandSet& strands, size_t s) {
    const std::vector<size_t> offsets = strands.Offsets();
    return strands.points_mm[offsets[s + 1] - 1].z();
  };
  const SeenTips tips = SeenTips::Find(hair, options.seen_tips);
  StrandGrowthSummary with_tips;
  const StrandSet ended =
      FieldGrowth(*field, nullptr, options, nullptr, nullptr, &tips).FromRoots(roots, &with_tips);
  ASSERT_EQ(ended.num_strands(), 2u);
  EXPECT_EQ(with_tips.stopped_seen_tip, 2) << "each at the tip of the seen strand it followed";
  EXPECT_NEAR(lowest_z(ended, 1), 150, 2.5) << "the lock's strand ends at its tip";
  EXPECT_NEAR(lowest_z(ended, 0), 100, 2.5) << "the curtain's runs to the curtain's end";
  StrandGrowthSummary without_tips;
  const StrandSet run_on =
      FieldGrowth(*field, nullptr, options, nullptr).FromRoots(roots, &without_tips);
  EXPECT_EQ(without_tips.stopped_seen_tip, 0);
  EXPECT_LT(lowest_z(run_on, 1), 140) << "without them it runs on past the lock";
  // A root just above the lock's tip: its strand has not grown min_strand_mm
  // when it passes the tip, so it runs on (with no minimum it is dropped).
  const std::vector<DirectedRoot> at_tip = {{{0, 24, 151}, {0, 0, -1}}};
  const FieldGrowth growth(*field, nullptr, options, nullptr, nullptr, &tips);
  const StrandSet kept = growth.FromRoots(at_tip, nullptr);
  ASSERT_EQ(kept.num_strands(), 1u);
  EXPECT_LT(lowest_z(kept, 0), 140);
  options.seen_tips.min_strand_mm = 0;
  StrandGrowthSummary no_minimum;
  EXPECT_EQ(growth.FromRoots(at_tip, &no_minimum).num_strands(), 0u);
  EXPECT_EQ(no_minimum.dropped_short, 1);
}

// Short hair lying on the side of the default ellipsoid head (scalp centre
// z = 330, hairline 8 deg above it over the ear, so near z = 338 there):
// segments 1 mm outside the head in the plane x > 0 from z = 360 down to
// z = 345; and, lower on the head at z = 200, a band of segments running
// around it (as a mis-segmented edge of a mannequin's neck gives).
// A point 1 mm outside the default ellipsoid head at (y, z), on its side (x > 0).
Eigen::Vector3f OnTheSkin(const HeadModel& head, double y, double z) {
  const double x = 78 * std::sqrt(std::max(0.0, 1 - std::pow((z - 250) / 115, 2)));
  const Eigen::Vector3d on_surface(x, y, z);
  const Eigen::Vector3d outside = head.KeepOutside(on_surface, 1);
  return Eigen::Vector3f(outside.cast<float>());
}

std::vector<StrandSegment> ShortHairOverTheEarAndABandBelow(const HeadModel& head) {
  std::vector<StrandSegment> segments;
  for (double y = -15; y <= 15; y += 3) {
    StrandSegment s;
    for (double z = 360; z >= 345; z -= 1.5) s.points_mm.push_back(OnTheSkin(head, y, z));
    segments.push_back(std::move(s));
  }
  StrandSegment band;
  for (double y = -20; y <= 20; y += 1.5) band.points_mm.push_back(OnTheSkin(head, y, 200));
  segments.push_back(std::move(band));
  return segments;
}

struct ShortHairScene {
  std::unique_ptr<HeadModel> head;
  std::vector<StrandSegment> hair;
  std::vector<DirectedRoot> roots;  // at the top of each strand of the short hair
  HybridOrientationField field;
};

ShortHairScene BuildShortHairScene(bool whole_head_in_volume) {
  HeadSpec spec;
  spec.scalp.defined = true;
  ShortHairScene scene;
  scene.head = HeadModel::Build(spec).value();
  scene.hair = ShortHairOverTheEarAndABandBelow(*scene.head);
  for (size_t k = 0; k + 1 < scene.hair.size(); ++k) {
    const std::vector<Eigen::Vector3f>& p = scene.hair[k].points_mm;
    scene.roots.push_back({p[0], (p[1] - p[0]).normalized()});
  }
  HybridFieldOptions options;
  options.whole_head_in_volume = whole_head_in_volume;
  scene.field =
      HybridOrientationField::Build(scene.hair, scene.roots, scene.head.get(), options).value();
  return scene;
}

TEST(HybridOrientationField, TheFieldDoesNotDependOnTheThreadCount) {
  const std::vector<StrandSegment> curtain = HangingCurtain();
  const std::vector<DirectedRoot> roots = {{{0, 0, 200}, {0, 0, -1}}};
  HybridFieldOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = HybridOrientationField::Build(curtain, roots, nullptr, one);
  const auto b = HybridOrientationField::Build(curtain, roots, nullptr, two);
  ASSERT_TRUE(a.ok() && b.ok());
  for (float z = 90; z <= 210; z += 7.5f) {
    for (float y = -25; y <= 25; y += 5) {
      const Eigen::Vector3f p(1.5f, y, z), previous(0, 0, -1);
      EXPECT_EQ(a->Interior(p, previous), b->Interior(p, previous));
      EXPECT_EQ(a->Surface(p, previous), b->Surface(p, previous));
    }
  }
}

TEST(HybridOrientationField, SkinBelowTheHairlineIsOutsideTheHairVolume) {
  const double bound = StrandGrowthOptions{}.volume_bound;
  const ShortHairScene above_hairline = BuildShortHairScene(false);
  const ShortHairScene whole_head = BuildShortHairScene(true);
  for (const double z : {320.0, 300.0, 280.0, 260.0, 240.0, 220.0}) {
    // Measured: I_d 23-65 above the hairline only, 0.3-1.4 with the whole head.
    EXPECT_GT(above_hairline.field.Distance(OnTheSkin(*above_hairline.head, 0, z)), 3 * bound)
        << "z " << z;
    EXPECT_LT(whole_head.field.Distance(OnTheSkin(*whole_head.head, 0, z)), 0.6 * bound)
        << "z " << z;
  }
  for (const double z : {355.0, 350.0})
    EXPECT_LT(above_hairline.field.Distance(OnTheSkin(*above_hairline.head, 0, z)), 0.5 * bound)
        << "under the hair, z " << z;
}

TEST(GrowStrandsInField, StrandsGrowingPastShortHairStopNearTheHairline) {
  const ShortHairScene scene = BuildShortHairScene(false);
  StrandGrowthSummary summary;
  const StrandSet strands = GrowStrandsInField(scene.field, scene.roots, scene.head.get(),
                                               StrandGrowthOptions{}, &summary);
  ASSERT_EQ(strands.num_strands(), scene.roots.size());
  EXPECT_EQ(summary.stopped_volume, static_cast<int64_t>(scene.roots.size()));
  double lowest = 1e9;
  for (const Eigen::Vector3f& p : strands.points_mm) lowest = std::min(lowest, double{p.z()});
  // The hair ends at z = 345 and the hairline lies near z = 338.
  EXPECT_GT(lowest, 330) << "a strand slid on down the skin";
}

TEST(GrowStrandsInField, WithMaxOffHairStrandsStopWhereTheSegmentsEnd) {
  // The whole head in I_d and no volume bound: only the rule can stop them.
  const ShortHairScene scene = BuildShortHairScene(true);
  StrandGrowthOptions options;
  options.volume_bound = 1e6;
  options.max_length_mm = 150;
  const auto lowest_end = [&](double max_off_hair_mm, StrandGrowthSummary* summary) {
    options.max_off_hair_mm = max_off_hair_mm;
    const StrandSet strands =
        GrowStrandsInField(scene.field, scene.roots, scene.head.get(), options, summary);
    EXPECT_EQ(strands.num_strands(), scene.roots.size());
    double lowest = 1e9;
    const std::vector<size_t> offsets = strands.Offsets();
    for (size_t s = 0; s + 1 < offsets.size(); ++s) {
      const Eigen::Vector3f& end = strands.points_mm[offsets[s + 1] - 1];
      lowest = std::min(lowest, double{end.z()});
      if (max_off_hair_mm > 0) {
        EXPECT_LT(scene.field.SegmentDistance(end), options.off_hair_mm)
            << "strand " << s << " keeps its stretch off the hair";
      }
    }
    return lowest;
  };
  StrandGrowthSummary with_rule, without_rule;
  const double stopped = lowest_end(10, &with_rule);
  const double run_on = lowest_end(0, &without_rule);
  // With the rule each strand is the start of the same strand grown without
  // it, and the vertex after its end lies off the hair.
  options.max_off_hair_mm = 10;
  const StrandSet cut = GrowStrandsInField(scene.field, scene.roots, scene.head.get(), options);
  options.max_off_hair_mm = 0;
  const StrandSet whole = GrowStrandsInField(scene.field, scene.roots, scene.head.get(), options);
  ASSERT_EQ(cut.num_strands(), whole.num_strands());
  const std::vector<size_t> cut_offsets = cut.Offsets(), whole_offsets = whole.Offsets();
  for (size_t s = 0; s < cut.num_strands(); ++s) {
    ASSERT_LT(cut.point_counts[s], whole.point_counts[s]) << "strand " << s;
    for (size_t i = 0; i < cut.point_counts[s]; ++i)
      ASSERT_EQ(cut.points_mm[cut_offsets[s] + i], whole.points_mm[whole_offsets[s] + i]);
    const Eigen::Vector3f& next = whole.points_mm[whole_offsets[s] + cut.point_counts[s]];
    EXPECT_GE(scene.field.SegmentDistance(next), options.off_hair_mm) << "strand " << s;
  }
  EXPECT_EQ(with_rule.stopped_off_hair, static_cast<int64_t>(scene.roots.size()));
  EXPECT_EQ(without_rule.stopped_off_hair, 0);
  // The hair ends at z = 345, 1 mm off the head (measured: the lowest end
  // 342 with the rule, 294 without).
  EXPECT_GT(stopped, 335) << "ends within off_hair_mm of the hair's end";
  EXPECT_LT(run_on, stopped - 20) << "without the rule the strands run on";
}

// A wavy seen strand (amplitude 1 mm, period 16 mm: finer than the field's
// 2 mm voxels resolve) hanging from z = 200 to z = 80, 6 mm beside a straight
// curtain; the mean distance from the strand grown at its root to the wavy
// polyline, over z in [100, 200].
double MeanMissOfAWavyStrand(double follow_radius_mm) {
  std::vector<StrandSegment> segments = HangingCurtain();
  for (StrandSegment& s : segments)
    for (Eigen::Vector3f& p : s.points_mm) p.x() -= 6;
  StrandSegment wavy;
  for (float z = 200; z >= 80; z -= 0.5f)
    wavy.points_mm.emplace_back(std::sin(2 * float(M_PI) * (200 - z) / 16), 0, z);
  segments.push_back(wavy);
  const std::vector<DirectedRoot> roots = {
      {wavy.points_mm[0], (wavy.points_mm[1] - wavy.points_mm[0]).normalized()}};
  const auto field = HybridOrientationField::Build(segments, roots, nullptr, HybridFieldOptions{});
  EXPECT_TRUE(field.ok()) << field.status().ToString();
  StrandGrowthOptions options;
  options.follow_radius_mm = follow_radius_mm;
  const StrandSet strands = GrowStrandsInField(*field, roots, nullptr, options);
  EXPECT_EQ(strands.num_strands(), 1u);
  double sum = 0;
  int count = 0;
  for (const Eigen::Vector3f& p : strands.points_mm) {
    if (p.z() < 100) continue;
    double nearest = 1e9;
    for (const Eigen::Vector3f& q : wavy.points_mm)
      nearest = std::min(nearest, double((q - p).norm()));
    sum += nearest, ++count;
  }
  EXPECT_GT(count, 90) << "the strand reaches z = 100";
  return count > 0 ? sum / count : 1e9;
}

// A block of hair hanging down z from z = 200 to 100 over x and y in
// [-24, 24]: straight seen strands 4 mm apart in x and y.
std::vector<StrandSegment> HangingBlock() {
  std::vector<StrandSegment> hair;
  for (float x = -24; x <= 24; x += 4) {
    for (float y = -24; y <= 24; y += 4) {
      StrandSegment s;
      for (float z = 200; z >= 100; z -= 2) s.points_mm.emplace_back(x, y, z);
      hair.push_back(std::move(s));
    }
  }
  return hair;
}

// Hair hanging down z from z = 200 to 100 (HangingBlock), roots between the seen strands (no seen
// strand within the follow radius). Where a curl is given, the strands wind on its helix about the
// field's direction: each stays its radius from a vertical centre line and is longer than its drop
// by 1 / cos(helix angle). Without one they hang straight.
TEST(GrowStrandsInField, WhereTheHairCurlsStrandsWindOnItsHelix) {
  const std::vector<StrandSegment> hair = HangingBlock();
  std::vector<DirectedRoot> roots;
  for (float y = -14; y <= 10; y += 8) roots.push_back({{2, y, 198}, {0, 0, -1}});
  const auto field = HybridOrientationField::Build(hair, roots, nullptr, HybridFieldOptions{});
  ASSERT_TRUE(field.ok()) << field.status().ToString();
  // 64 deg off the axis: more than the 60 deg within which a strand follows a seen one.
  const Curl curl{4, 12, 1};
  const CurlField curls = CurlField::Everywhere(curl);
  // Strands wind only as deep in the hair as curl.min_depth_mm: past the
  // field's grid, nowhere.
  StrandGrowthOptions too_deep;
  too_deep.curl.min_depth_mm = 1000;
  const StrandSet straight =
      FieldGrowth(*field, nullptr, too_deep, nullptr, &curls).FromRoots(roots, nullptr);
  ASSERT_EQ(straight.num_strands(), roots.size());
  for (size_t k = 0; k < roots.size(); ++k) {
    const Eigen::Vector3f tip = straight.points_mm[straight.Offsets()[k + 1] - 1];
    EXPECT_NEAR(straight.StrandLengths()[k] / (roots[k].position_mm.z() - tip.z()), 1.0, 0.02)
        << "strand " << k;
  }
  const StrandGrowthOptions options;
  for (const CurlField* given : {&curls, static_cast<const CurlField*>(nullptr)}) {
    const StrandSet strands =
        FieldGrowth(*field, nullptr, options, nullptr, given).FromRoots(roots, nullptr);
    ASSERT_EQ(strands.num_strands(), roots.size());
    const std::vector<double> lengths = strands.StrandLengths();
    const std::vector<size_t> offsets = strands.Offsets();
    for (size_t k = 0; k < roots.size(); ++k) {
      const Eigen::Vector3f tip = strands.points_mm[offsets[k + 1] - 1];
      const double drop = roots[k].position_mm.z() - tip.z();
      ASSERT_GT(drop, 50) << "strand " << k;
      if (given == nullptr) {
        EXPECT_NEAR(lengths[k] / drop, 1.0, 0.02) << "strand " << k;
        continue;
      }
      EXPECT_NEAR(lengths[k] / drop, 1 / std::cos(curl.HelixAngle()), 0.15) << "strand " << k;
      // Away from the root, the strand keeps the radius about its mean line.
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      const size_t first = offsets[k] + 20, last = offsets[k + 1];
      for (size_t i = first; i < last; ++i) mean += strands.points_mm[i].head<2>().cast<double>();
      mean /= static_cast<double>(last - first);
      for (size_t i = first; i < last; ++i)
        EXPECT_NEAR((strands.points_mm[i].head<2>().cast<double>() - mean).norm(), curl.radius_mm,
                    1.0)
            << "strand " << k << " vertex " << i - offsets[k];
    }
  }
}

// The hair block above, seen from its front (y = +24) by four cameras; roots
// 2 mm behind the seen face wind on a 6 mm helix. Left alone, the helices
// started there swing out in front of the face, where the cameras see
// through; kept out of the free space, they wind behind it.
TEST(GrowStrandsInField, HelicesWindBehindTheSeenFaceNotInFrontOfIt) {
  const std::vector<StrandSegment> hair = HangingBlock();
  std::vector<DirectedRoot> roots;
  for (float x = -16; x <= 16; x += 4) roots.push_back({{x, 22, 198}, {0, 0, -1}});
  const auto field = HybridOrientationField::Build(hair, roots, nullptr, HybridFieldOptions{});
  ASSERT_TRUE(field.ok()) << field.status().ToString();
  const CurlField curls = CurlField::Everywhere(Curl{6, 20, 1});
  FreeSpaceOptions carve;
  carve.min_views = 4;  // every camera
  const FreeSpace free(front_views::Cameras(4, 150), front_views::FrontFace(24, 24, 100, 200, 4),
                       carve);
  const StrandGrowthOptions options;
  // The furthest any vertex below the roots lies out in front (y, mm), and
  // how many of those vertices lie in the free space.
  struct Out {
    double furthest = -1e9;
    int in_free_space = 0;
  };
  const auto grown_out = [&](const FreeSpace* given, StrandGrowthSummary* summary) {
    const StrandSet strands = FieldGrowth(*field, nullptr, options, nullptr, &curls, nullptr, given)
                                  .FromRoots(roots, summary);
    EXPECT_EQ(strands.num_strands(), roots.size());
    Out out;
    for (const Eigen::Vector3f& p : strands.points_mm) {
      if (!(p.z() < 190 && p.z() > 110)) continue;
      out.furthest = std::max(out.furthest, double(p.y()));
      out.in_free_space += free.Free(p.cast<double>());
    }
    return out;
  };
  StrandGrowthSummary left, kept;
  const Out left_out = grown_out(nullptr, &left);
  const Out kept_out = grown_out(&free, &kept);
  // Measured: 29.8 mm out left alone, 27.5 kept; 14 vertices in the free
  // space left alone, 8 kept (where 4 moves a step do not get the next
  // vertex out, and the cache's cells blur the free space's edge).
  EXPECT_GT(left_out.furthest, 24 + carve.margin_mm + 2) << "the test needs helices that swing out";
  EXPECT_GE(left_out.in_free_space, 10) << "the test needs helices that swing out";
  // The cache's cell (1 mm, its centre up to 0.87 mm off) and a step's length.
  EXPECT_LT(kept_out.furthest, 24 + carve.margin_mm + 2) << "left alone: " << left_out.furthest;
  EXPECT_LE(3 * kept_out.in_free_space, 2 * left_out.in_free_space);
  EXPECT_EQ(left.helix_moves_from_free_space, 0);
  EXPECT_GT(kept.helix_moves_from_free_space, 0);
}

TEST(GrowStrandsInField, StrandsFollowASeenStrandCloserThanTheGridAlone) {
  const double following = MeanMissOfAWavyStrand(1.0);
  const double field_only = MeanMissOfAWavyStrand(0.0);
  // Measured: 0.80 mm following the seen strand, 1.11 mm on the grid alone.
  EXPECT_LT(following, 0.8 * field_only);
}

// Seen strands down the side of the default ellipsoid head (x > 0), 3 mm
// apart, 1 mm off the skin: at y = -15 .. -3 from near the crown (z = 362) down to
// z = 300, grown from roots at their tops; at y = 0 .. 12 from z = 334, below
// the hairline (near z = 338 there), down, where no root is and no root's
// strand passes.
struct SideHairScene {
  std::unique_ptr<HeadModel> head;
  std::vector<StrandSegment> hair;  // the rooted half, then the other
  std::vector<DirectedRoot> roots;
  HybridOrientationField field;
  std::vector<StrandSegment> Unrooted() const {
    return std::vector<StrandSegment>(hair.begin() + static_cast<ptrdiff_t>(roots.size()),
                                      hair.end());
  }
};

StrandSegment DownTheSide(const HeadModel& head, double y, double z_top, double off_skin_mm) {
  StrandSegment s;
  for (double z = z_top; z >= 300; z -= 2) {
    const double x = 78 * std::sqrt(std::max(0.0, 1 - std::pow((z - 250) / 115, 2)));
    s.points_mm.push_back(head.KeepOutside({x, y, z}, off_skin_mm).cast<float>());
  }
  return s;
}

SideHairScene BuildSideHairScene() {
  HeadSpec spec;
  spec.scalp.defined = true;
  SideHairScene scene;
  scene.head = HeadModel::Build(spec).value();
  for (double y = -15; y <= -3; y += 3) {
    scene.hair.push_back(DownTheSide(*scene.head, y, 362, 1));
    const std::vector<Eigen::Vector3f>& p = scene.hair.back().points_mm;
    scene.roots.push_back({p[0], (p[1] - p[0]).normalized()});
  }
  for (double y = 0; y <= 12; y += 3) scene.hair.push_back(DownTheSide(*scene.head, y, 334, 1));
  scene.field =
      HybridOrientationField::Build(scene.hair, scene.roots, scene.head.get(), HybridFieldOptions{})
          .value();
  return scene;
}

// The farthest a vertex of `segment` lies from the nearest vertex of `strands` (mm).
double FarthestMiss(const StrandSegment& segment, const StrandSet& strands) {
  double farthest = 0;
  for (const Eigen::Vector3f& v : segment.points_mm) {
    double nearest = 1e9;
    for (const Eigen::Vector3f& p : strands.points_mm)
      nearest = std::min(nearest, double((p - v).norm()));
    farthest = std::max(farthest, nearest);
  }
  return farthest;
}

StrandSet GrowAndCover(const SideHairScene& scene, const StrandGrowthOptions& options,
                       StrandGrowthSummary* summary) {
  const FieldGrowth growth(scene.field, scene.head.get(), options, nullptr);
  StrandSet strands = growth.FromRoots(scene.roots, summary);
  EXPECT_EQ(strands.num_strands(), scene.roots.size());
  growth.ThroughUncoveredSegments(scene.hair, &strands, summary);
  return strands;
}

TEST(FieldGrowth, SeenStrandsNoRootsStrandPassesAlongGetStrandsFromTheScalp) {
  const SideHairScene scene = BuildSideHairScene();
  StrandGrowthOptions options;
  options.cover.enabled = false;
  StrandGrowthSummary paper;
  const StrandSet from_roots = GrowAndCover(scene, options, &paper);
  EXPECT_EQ(paper.cover_strands, 0);
  for (const StrandSegment& seen : scene.Unrooted())
    EXPECT_GT(FarthestMiss(seen, from_roots), 2) << "not covered by the roots' strands";

  options.cover.enabled = true;
  StrandGrowthSummary covered;
  const StrandSet strands = GrowAndCover(scene, options, &covered);
  EXPECT_GE(covered.cover_strands - covered.cover_grafted, 3) << "most traced back to the scalp";
  EXPECT_EQ(covered.cover_no_root, 0);
  EXPECT_EQ(covered.strands, static_cast<int64_t>(strands.num_strands()));
  for (const StrandSegment& seen : scene.Unrooted()) EXPECT_LT(FarthestMiss(seen, strands), 2);
  options.threads = 1;
  StrandGrowthSummary one_thread;
  const StrandSet same = GrowAndCover(scene, options, &one_thread);
  EXPECT_EQ(same.point_counts, strands.point_counts) << "the same strands on any thread count";
  EXPECT_EQ(same.points_mm, strands.points_mm);
  const std::vector<size_t> offsets = strands.Offsets();
  for (size_t s = scene.roots.size(); s < strands.num_strands(); ++s) {
    const Eigen::Vector3d root = strands.points_mm[offsets[s]].cast<double>();
    Eigen::Vector3d outward;
    EXPECT_LT(scene.head->SignedDistance(root, &outward), options.cover.root_reach_mm + 0.01)
        << "strand " << s;
    EXPECT_TRUE(scene.head->OnScalp(root)) << "strand " << s;
    EXPECT_GT(root.z(), 336) << "strand " << s << " comes from above its seen strand's top";
  }
}

TEST(FieldGrowth, ASeenStrandNoTraceBringsBackIsGraftedOnTheStrandBesideIt) {
  const SideHairScene scene = BuildSideHairScene();
  StrandGrowthOptions options;
  // Nearer the head than the growth keeps vertices from it: no trace ends at the scalp.
  options.cover.root_reach_mm = 0.5 * options.head_clearance_mm;
  StrandGrowthSummary summary;
  const StrandSet strands = GrowAndCover(scene, options, &summary);
  EXPECT_GE(summary.cover_strands, 1);
  EXPECT_EQ(summary.cover_grafted, summary.cover_strands);
  for (const StrandSegment& seen : scene.Unrooted()) EXPECT_LT(FarthestMiss(seen, strands), 2);
  double longest_seen_edge = 0;
  for (const StrandSegment& seen : scene.hair)
    for (size_t i = 1; i < seen.points_mm.size(); ++i)
      longest_seen_edge =
          std::max(longest_seen_edge, double((seen.points_mm[i] - seen.points_mm[i - 1]).norm()));
  // Each leaves the scalp where a strand grown from a root does.
  const std::vector<size_t> offsets = strands.Offsets();
  for (size_t s = scene.roots.size(); s < strands.num_strands(); ++s) {
    const Eigen::Vector3f& root = strands.points_mm[offsets[s]];
    EXPECT_TRUE(std::any_of(scene.roots.begin(), scene.roots.end(),
                            [&](const DirectedRoot& r) { return r.position_mm == root; }))
        << "strand " << s;
    // The bridge onto the seen strand, 3 mm beside the one grafted on, is
    // no coarser than the seen strands' vertices and bends gently.
    for (size_t i = offsets[s] + 1; i + 1 < offsets[s + 1]; ++i) {
      const Eigen::Vector3f in = strands.points_mm[i] - strands.points_mm[i - 1],
                            out = strands.points_mm[i + 1] - strands.points_mm[i];
      EXPECT_LT(in.norm(), longest_seen_edge + 0.01)
          << "strand " << s << " vertex " << i - offsets[s];
      EXPECT_GT(in.normalized().dot(out.normalized()), std::cos(45 * M_PI / 180))
          << "strand " << s << " vertex " << i - offsets[s];
    }
  }
}

TEST(StrandReconstructionOptions, RootElevationOutsideItsRangeIsRefused) {
  StrandReconstructionOptions options;
  for (const double elevation : {0.0, -10.0, 95.0, std::nan("")}) {
    options.root_elevation_deg = elevation;
    const Status status = options.Check();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << elevation;
    EXPECT_NE(status.ToString().find("root_elevation_deg"), std::string::npos) << status.ToString();
  }
  for (const double elevation : {30.0, 90.0}) {
    options.root_elevation_deg = elevation;
    EXPECT_TRUE(options.Check().ok()) << elevation;
  }
}

// The reconstruction options refuse a bad value with InvalidArgument naming
// the field; a nested struct's field is named after the field holding it.
TEST(ReconstructionOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(MixtureFitOptions{}.Check().ok());
  EXPECT_TRUE(StrandPreviewOptions{}.Check().ok());
  EXPECT_TRUE(StrandOverlayOptions{}.Check().ok());
  EXPECT_TRUE(SampleMatchOptions{}.Check().ok());
  EXPECT_TRUE(StrandReconstructionOptions{}.Check().ok());
  EXPECT_TRUE(PointReconstructionOptions{}.Check().ok());
  {
    StrandReconstructionOptions o;
    o.given_curl = Curl{6, 20, 0};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "given_curl"));
    o.growth.curl.min_handedness_agreement = 0.4;
    o.given_curl = Curl{};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "min_handedness_agreement"));
  }
  {
    MixtureFitOptions o;
    o.variance_floor = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "variance_floor"));
    o = MixtureFitOptions{};
    o.relative_tolerance = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "relative_tolerance"));
    o = MixtureFitOptions{};
    o.kmeans_attempts = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "kmeans_attempts"));
  }
  EXPECT_TRUE(IsInvalidNaming(ColmapReadOptions{}.Check(), "images_dir"));
  EXPECT_TRUE((ColmapReadOptions{"images", ""}.Check().ok()));
  {
    StrandPreviewOptions o;
    o.view_px = 4;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "view_px"));
    o = StrandPreviewOptions{};
    o.azimuths_deg = {0, std::nan("")};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "azimuths_deg"));
    o = StrandPreviewOptions{};
    o.max_strands = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "max_strands"));
  }
  {
    StrandOverlayOptions o;
    o.opacity = 1.5;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "opacity"));
    o = StrandOverlayOptions{};
    o.view_px = 100000;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "view_px"));
  }
  {
    SampleMatchOptions o;
    o.threads = 0;
    EXPECT_TRUE(o.Check().ok()) << "threads below 1 run on one thread";
  }
  {
    StrandReconstructionOptions o;
    o.growth.step_mm = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "growth: strand step_mm"));
    o = StrandReconstructionOptions{};
    o.growth.tip_skin_margin_px = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "tip_skin_margin_px"));
    o = StrandReconstructionOptions{};
    o.wisps.spacing_mm = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "wisps: wisp spacing_mm"));
  }
  {
    PointReconstructionOptions o;
    o.mvs.samples = 2;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "mvs: mvs samples"));
    o = PointReconstructionOptions{};
    o.segmentation.border_px = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "segmentation: segmentation border_px"));
  }
}

// The entry points taking the new options refuse bad ones before any work.
TEST(ReconstructionOptions, EntryPointsCheckTheirOptions) {
  StrandPreviewOptions preview;
  preview.view_px = 0;
  const Result<cv::Mat> picture = RenderStrandPreview({}, {}, preview);
  ASSERT_FALSE(picture.ok());
  EXPECT_NE(picture.status().message().find("view_px"), std::string::npos);

  StrandOverlayOptions overlay;
  overlay.max_strands = 0;
  const Result<cv::Mat> over = RenderStrandsOverViews({}, StrandSet{}, overlay);
  ASSERT_FALSE(over.ok());
  EXPECT_NE(over.status().message().find("max_strands"), std::string::npos);

  const Result<ReconstructionInput> colmap = ReadColmapModel("/nonexistent-model", {});
  ASSERT_FALSE(colmap.ok());
  EXPECT_EQ(colmap.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(colmap.status().message().find("images_dir"), std::string::npos);

  MixtureFitOptions mixture;
  mixture.max_iterations = 0;
  const Result<GaussianMixture> fit = FitGaussianMixture(cv::Mat1f(100, 3, 1.0f), mixture);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.status().message().find("max_iterations"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
