// The subject's head in the turntable frame (mm): an ellipsoid, or a
// triangle mesh (a mannequin head such as ../shared/data/strands/Bangs_head.ply)
// placed by a pose (core/head_spec.h). One interface for the simulated rig's
// renderer and wig (ray casting, shading normals, roots on the scalp) and for
// reconstruction (strand roots on the scalp, hair kept outside the head).
//
// The scalp is the part of the head's surface hair grows from: above a
// hairline whose elevation (seen from the scalp centre, 0 = level with it,
// 90 = straight up) runs from the forehead over the temples and above the ears
// to the nape, minus a parting line, so the face, the ears and the neck stay bare.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <random>

#include "core/head_spec.h"
#include "core/mesh_bvh.h"
#include "core/status.h"
#include "core/triangle_mesh.h"

namespace hairrig {

struct HeadHit {
  double t = 0;            // along the ray (units of its direction)
  Eigen::Vector3d normal;  // outward shading normal, unit (turntable frame)
};

class HeadModel {
 public:
  // Loads the mesh (if the spec gives one), builds its BVH and its signed
  // distance grid (2 mm; about 0.3 s for 8,000 triangles). Errors name the mesh file.
  static Result<std::unique_ptr<HeadModel>> Build(const HeadSpec& head);
  ~HeadModel();

  const HeadSpec& head() const { return head_; }
  bool is_mesh() const { return !head_.mesh_file.empty(); }
  // The mesh in the turntable frame; for an ellipsoid, a tessellation of it
  // (for bounds and root sampling only: the ellipsoid is ray cast exactly).
  const TriangleMesh& mesh() const { return mesh_; }

  // Nearest hit of origin + t dir with t in (t_min, t_max) (turntable frame).
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                 double t_max, HeadHit* hit) const;
  // Signed distance to the surface (mm, negative inside) and the outward
  // direction (unit). Exact for an ellipsoid's level sets near it (first order); a
  // mesh's is trilinear in its grid (within about 1 mm near the surface;
  // clamped to +-kBandMm, and the grid's box distance outside the grid).
  double SignedDistance(const Eigen::Vector3d& p, Eigen::Vector3d* outward) const;
  // Within about `margin_mm` of the surface, or inside (an ellipsoid: inside
  // the ellipsoid grown by the margin).
  bool IsNear(const Eigen::Vector3d& p, double margin_mm) const;
  // `p` moved outward until it is `margin_mm` outside the surface (unchanged if it already is).
  Eigen::Vector3d KeepOutside(const Eigen::Vector3d& p, double margin_mm) const;

  // A point on the scalp, uniform by area, with its outward normal. The
  // region is the spec's scalp; ScalpSide gives the side of the parting
  // (-1, +1, or 0 without a parting).
  Eigen::Vector3d SampleScalp(std::mt19937_64& rng, Eigen::Vector3d* normal) const;
  bool OnScalp(const Eigen::Vector3d& p) const;
  // Seen from the scalp centre, p lies above the hairline (the parting
  // counts as above): the skull hair grows from or covers, not the face, the
  // ears or the neck. True everywhere for a head without a scalp region.
  bool AboveHairline(const Eigen::Vector3d& p) const;
  int ScalpSide(const Eigen::Vector3d& p) const;
  // The scalp's frame: up (+z), face direction and the side axis (up x face),
  // and the centre directions are measured from.
  Eigen::Vector3d ScalpCenter() const { return head_.scalp.center_turntable_mm; }
  // Elevation (deg) of p seen from the scalp centre, and its azimuth from the face (deg, 0..180).
  void ScalpAngles(const Eigen::Vector3d& p, double* elevation_deg, double* azimuth_deg) const;

  static constexpr double kBandMm = 12.0;

 private:
  explicit HeadModel(const HeadSpec& head) : head_(head) {}
  Status BuildDistanceGrid();
  double GridDistance(const Eigen::Vector3d& p) const;

  HeadSpec head_;
  TriangleMesh mesh_;
  Eigen::Vector3d mesh_centre_mm_ = Eigen::Vector3d::Zero();  // centre of the mesh's bounds
  MeshBvh bvh_;
  std::vector<Eigen::Vector3d> vertex_normals_;
  std::vector<double> cumulative_scalp_area_;  // per triangle, for sampling
  std::vector<uint32_t> scalp_triangles_;
  // Signed distance grid (mesh only).
  Eigen::Vector3d grid_origin_;
  Eigen::Vector3i grid_size_;
  double grid_step_mm_ = 2.0;
  std::vector<float> grid_;
};

}  // namespace hairrig
