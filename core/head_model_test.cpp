#include "core/head_model.h"

#include <gtest/gtest.h>

#include <random>

#include "core/head_config.h"

namespace hairrig {
namespace {

// The lab's mannequin (etc/heads/mannequin.yaml), with a side parting.
HeadSpec Mannequin() {
  auto head = LoadHeadFile("etc/heads/mannequin.yaml");
  EXPECT_TRUE(head.ok()) << head.status().ToString();
  HeadSpec spec = head.ok() ? *head : HeadSpec{};
  spec.scalp.parting = true;
  spec.scalp.parting_offset_deg = 12;
  return spec;
}

// The mannequin's distance grid: points pushed out by KeepOutside are outside
// the mesh (the BVH's parity test) and near the surface they were pushed to.
TEST(HeadModel, TheMeshHeadKeepsPointsOutsideAndKnowsInsideFromOutside) {
  auto head = HeadModel::Build(Mannequin());
  ASSERT_TRUE(head.ok()) << head.status().ToString();
  ASSERT_TRUE((*head)->is_mesh());
  const MeshBvh bvh((*head)->mesh());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Vector3d lo = (*head)->mesh().MinCorner(), hi = (*head)->mesh().MaxCorner();
  int inside = 0, checked = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p =
        0.5 * (lo + hi) + 0.5 * (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const double d = (*head)->SignedDistance(p, nullptr);
    if (std::abs(d) < 3.0) continue;  // within the grid's resolution of the surface
    ++checked;
    EXPECT_EQ(d < 0, bvh.Contains(p)) << "sign of the distance at " << p.transpose();
    if (d < 0) {
      ++inside;
      const Eigen::Vector3d q = (*head)->KeepOutside(p, 1.0);
      EXPECT_FALSE(bvh.Contains(q)) << p.transpose() << " -> " << q.transpose();
    }
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(checked, 1000);
}

// Roots lie on the scalp: above the hairline, off the parting, on the surface.
TEST(HeadModel, ScalpSamplesLieOnTheHeadAboveTheHairline) {
  auto head = HeadModel::Build(Mannequin());
  ASSERT_TRUE(head.ok());
  std::mt19937_64 rng(9);
  int left = 0, right = 0;
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3d n;
    const Eigen::Vector3d p = (*head)->SampleScalp(rng, &n);
    EXPECT_TRUE((*head)->OnScalp(p));
    EXPECT_LT(std::abs((*head)->SignedDistance(p, nullptr)), 1.5) << "on the surface";
    double elevation, azimuth;
    (*head)->ScalpAngles(p, &elevation, &azimuth);
    EXPECT_GT(elevation, -31) << "no roots below the nape's hairline";
    if (azimuth < 10) {  // the hairline is at 32 deg over the face, 22 at the temples
      EXPECT_GT(elevation, 29.5) << "the forehead is bare";
    }
    (*head)->ScalpSide(p) > 0 ? ++left : ++right;
  }
  EXPECT_GT(left, 300);
  EXPECT_GT(right, 300);
}

// Above the hairline: the skull, the parting included; not the face or the neck.
TEST(HeadModel, AboveTheHairlineIsTheSkullWithItsPartingButNotTheFaceOrNeck) {
  HeadSpec spec;  // the default ellipsoid, scalp centre (0, 0, 330), face towards -y
  spec.scalp.defined = true;
  auto head = HeadModel::Build(spec);
  ASSERT_TRUE(head.ok()) << head.status().ToString();
  const HeadModel& h = **head;
  const Eigen::Vector3d crown(0, 0, 365), parting(0, -30, 362), back(0, 95, 300);
  EXPECT_TRUE(h.AboveHairline(crown));
  EXPECT_TRUE(h.AboveHairline(parting));
  EXPECT_FALSE(h.OnScalp(parting)) << "the parting is bare";
  EXPECT_TRUE(h.AboveHairline(back)) << "the nape's hairline is 28 deg below the centre";
  EXPECT_FALSE(h.AboveHairline(Eigen::Vector3d(0, -95, 300))) << "the face";
  EXPECT_FALSE(h.AboveHairline(Eigen::Vector3d(0, 0, 150))) << "the neck";
  EXPECT_TRUE(h.AboveHairline(h.ScalpCenter())) << "the centre itself";
  HeadSpec bare;  // no scalp region: the whole head
  auto no_scalp = HeadModel::Build(bare);
  ASSERT_TRUE(no_scalp.ok());
  EXPECT_TRUE((*no_scalp)->AboveHairline(Eigen::Vector3d(0, 0, 150)));
}

TEST(HeadModel, AMissingMeshNamesTheField) {
  HeadSpec h;
  h.mesh_file = "/nonexistent/head.ply";
  auto head = HeadModel::Build(h);
  ASSERT_FALSE(head.ok());
  EXPECT_NE(head.status().message().find("head.mesh"), std::string::npos)
      << head.status().message();
}

}  // namespace
}  // namespace hairrig
