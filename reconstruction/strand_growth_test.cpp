#include "reconstruction/strand_growth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/head_spec.h"
#include "reconstruction/strand_reconstruction.h"

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

}  // namespace
}  // namespace hairrig
