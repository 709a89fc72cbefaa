// Triangle meshes (a mannequin head, a scalp) in millimetres, in the frame the
// file or the producer states. Read from PLY (a `vertex` element with x, y, z
// and a `face` element with a `vertex_indices` list; polygons are fanned into
// triangles) or Wavefront OBJ (`v` and `f` lines; texture and normal indices
// ignored). Every count is checked against the file's bytes before anything is
// allocated; a face naming a vertex that does not exist, a non-finite
// coordinate or a mesh without triangles is CorruptData naming the file and the
// record.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_mm;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside

  size_t num_triangles() const { return triangles.size(); }
  // The corners of triangle `t`.
  const Eigen::Vector3d& Corner(size_t t, int k) const {
    return vertices_mm[triangles[t][static_cast<size_t>(k)]];
  }
  // Unit normal of triangle `t` by its winding (zero for a degenerate one).
  Eigen::Vector3d FaceNormal(size_t t) const;
  double FaceArea(size_t t) const;
  // Axis-aligned bounds of the vertices.
  Eigen::Vector3d MinCorner() const;
  Eigen::Vector3d MaxCorner() const;
  // Every vertex mapped through `to_from_mesh`.
  void Transform(const Rigid3d& to_from_mesh);
  // Indices in range, coordinates finite, at least one triangle.
  Status Check(const std::string& name) const;
};

// PLY or OBJ by the file's extension (.ply, .obj).
Result<TriangleMesh> ReadTriangleMesh(const std::string& path);
// `name` is for messages.
Result<TriangleMesh> DecodePlyMesh(const std::vector<uint8_t>& bytes, const std::string& name);
Result<TriangleMesh> DecodeObjMesh(const std::string& text, const std::string& name);

// A closed ellipsoid (centre, semi-axes along x, y, z) tessellated by latitude
// and longitude: `rings` bands from pole to pole, `segments` around. Outward winding.
TriangleMesh MakeEllipsoidMesh(const Eigen::Vector3d& center_mm, const Eigen::Vector3d& radii_mm,
                               int rings, int segments);

}  // namespace hairrig
