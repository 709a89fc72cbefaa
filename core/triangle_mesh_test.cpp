#include "core/triangle_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/mesh_bvh.h"

namespace hairrig {
namespace {

std::vector<uint8_t> Bytes(const std::string& s) { return {s.begin(), s.end()}; }

TEST(TriangleMesh, AsciiPlyPolygonsAreFannedIntoTriangles) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float "
      "z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  auto mesh = DecodePlyMesh(Bytes(ply), "quad.ply");
  ASSERT_TRUE(mesh.ok()) << mesh.status().ToString();
  EXPECT_EQ(mesh->num_triangles(), 2u);
  EXPECT_NEAR(mesh->FaceArea(0) + mesh->FaceArea(1), 1.0, 1e-12);
  EXPECT_NEAR(mesh->FaceNormal(0).z(), 1.0, 1e-12);
}

TEST(TriangleMesh, BadFilesNameTheFileAndTheRecord) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
      "z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n";
  auto bad_index = DecodePlyMesh(Bytes(header + "3 0 1 7\n"), "head.ply");
  ASSERT_FALSE(bad_index.ok());
  EXPECT_NE(bad_index.status().message().find("head.ply: face 0 names vertex 7"), std::string::npos)
      << bad_index.status().message();
  auto truncated = DecodePlyMesh(Bytes(header), "head.ply");
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.status().message().find("head.ply"), std::string::npos);
  const std::string huge =
      "ply\nformat binary_little_endian 1.0\nelement vertex 9000000000000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  EXPECT_FALSE(DecodePlyMesh(Bytes(huge), "huge.ply").ok())
      << "a count beyond the file's bytes is refused";
  auto nan = DecodeObjMesh("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "nan.obj");
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.status().message().find("nan.obj:3"), std::string::npos) << nan.status().message();
  auto bad_face = DecodeObjMesh("v 0 0 0\nf 1 2\n", "bad.obj");
  ASSERT_FALSE(bad_face.ok());
  EXPECT_NE(bad_face.status().message().find("bad.obj:2"), std::string::npos);
}

TEST(TriangleMesh, ObjFacesWithTextureIndicesAndNegativeIndices) {
  auto mesh =
      DecodeObjMesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf -3 -2 -1\n", "tri.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().ToString();
  EXPECT_EQ(mesh->num_triangles(), 2u);
  EXPECT_EQ(mesh->triangles[1][0], 0u);
}

// Rays from outside an ellipsoid's tessellation hit it where the exact
// ellipsoid is, within the tessellation's sagitta.
TEST(MeshBvh, RaysHitATessellatedEllipsoidWhereTheEllipsoidIs) {
  const Eigen::Vector3d c(10, -20, 300), r(78, 95, 115);
  const TriangleMesh mesh = MakeEllipsoidMesh(c, r, 96, 192);
  const MeshBvh bvh(mesh);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d origin = c + Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 600;
    const Eigen::Vector3d target =
        c + 0.9 * Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(r) / std::sqrt(3.0);
    const Eigen::Vector3d dir = target - origin;
    MeshRayHit hit;
    ASSERT_TRUE(bvh.Intersect(origin, dir, 0, 1e9, &hit)) << "the ray aims inside the ellipsoid";
    const Eigen::Vector3d p = origin + hit.t * dir;
    EXPECT_NEAR((p - c).cwiseQuotient(r).norm(), 1.0, 2e-3);
    EXPECT_TRUE(bvh.Occluded(origin, dir, 0, 1e9));
    ++hits;
  }
  EXPECT_EQ(hits, 2000);
  EXPECT_TRUE(bvh.Contains(c));
  EXPECT_FALSE(bvh.Contains(c + Eigen::Vector3d(0, 0, 130)));
  MeshRayHit miss;
  EXPECT_FALSE(
      bvh.Intersect(c + Eigen::Vector3d(0, 0, 500), Eigen::Vector3d(1, 0, 0), 0, 1e9, &miss));
}

// The real mannequin head that goes with the CT-scanned bangs: millimetres,
// +x up (neck base at x = -42 mm, crown at x = 245 mm), face towards -y.
TEST(TriangleMesh, TheRealHeadMeshReads) {
  const std::string path =
      "etc/assets/mannequin_head.ply";  // Bangs_head.ply, vendored with its notice
  auto mesh = ReadTriangleMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().ToString();
  EXPECT_EQ(mesh->vertices_mm.size(), 3943u);
  EXPECT_EQ(mesh->num_triangles(), 7694u);
  EXPECT_NEAR(mesh->MinCorner().x(), -42.4, 0.1);
  EXPECT_NEAR(mesh->MaxCorner().x(), 244.9, 0.1);
  const MeshBvh bvh(*mesh);
  EXPECT_TRUE(bvh.Contains(Eigen::Vector3d(150, 135, 121))) << "the skull's centre is inside";
}

}  // namespace
}  // namespace hairrig
