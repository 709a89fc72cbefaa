// Bao & Qi 2017's hybrid orientation field (Sec. IV-A) on a regular voxel
// grid (2 mm by default) over the hair's bounding box, in the points' frame
// (mm):
//   V_i  interior orientation field: the directions of the directed strand
//        segments and of the roots (their first direction) fixed in the voxels
//        they occupy (Dirichlet), the rest by a Laplace solve;
//   S_s  surface-structure field: the same from the directed ribbons only;
//   I_d  interior distance field: 0 in voxels a segment or the head occupies,
//        the Euclidean distance to them on the box's faces, a Laplace solve
//        between. By default only the head above its hairline
//        (HeadModel::AboveHairline) counts: the paper's whole head keeps I_d
//        near 0 along the face and the neck, so a strand that has passed the
//        hair's end slides down the skin to its maximum length;
//   d_s  the distance to the nearest ribbon vertex (the weights of Eq. 1).
// Beside the grids it keeps the segments' vertices and tangents for
// NearestSegmentTangent, which strand growth follows (strand_growth.h).
// O_g, the growing direction, belongs to each growing strand
// (strand_growth.h).
//
// The paper diffuses tensors V = v v^T, which forget the root-to-tip sign;
// `directed` diffuses the directed vectors instead, so strands follow the
// segments' direction as well as their line. Both are available; the
// strand bench measures them side by side.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

struct HybridFieldOptions {
  double voxel_mm = 2.0;
  double margin_mm = 20;      // around the segments' and the scalp's bounds
  bool directed = true;       // diffuse vectors (else the paper's tensors v v^T)
  int sweeps_per_level = 40;  // Gauss-Seidel (SOR) sweeps at each level of the coarse-to-fine solve
  double ribbon_min_length_mm =
      20;  // segments at least this long stand for the directed ribbons of S_s
  bool whole_head_in_volume =
      false;  // I_d is 0 in the whole head (the paper), not above the hairline only
  // The interior and surface solves run side by side on 2 threads; the
  // result does not depend on it.
  int threads = 2;
  Status Check() const;
};

struct DirectedRoot {
  Eigen::Vector3f position_mm;
  Eigen::Vector3f direction;  // unit, out of the scalp: the strand's first direction
};

class HybridOrientationField {
 public:
  // `segments` run root to tip (strand_direction.h). `head` may be null
  // (then only segments bound I_d). InvalidArgument for an empty input or a
  // grid of more than 64 million voxels.
  static Result<HybridOrientationField> Build(const std::vector<StrandSegment>& segments,
                                              const std::vector<DirectedRoot>& roots,
                                              const HeadModel* head,
                                              const HybridFieldOptions& options);

  // Trilinear samples at p (outside the grid: the nearest face's). With
  // tensors, the principal direction signed to agree with `previous`.
  Eigen::Vector3f Interior(const Eigen::Vector3f& p, const Eigen::Vector3f& previous) const;
  Eigen::Vector3f Surface(const Eigen::Vector3f& p, const Eigen::Vector3f& previous) const;
  double Distance(const Eigen::Vector3f& p) const;  // I_d (mm-like units)
  Eigen::Vector3f DistanceGradient(
      const Eigen::Vector3f& p) const;                    // grad I_d (central differences)
  double RibbonDistance(const Eigen::Vector3f& p) const;  // d_s (mm)
  // To the nearest voxel a segment occupies (mm; chamfer distance between
  // voxel centres, trilinear between them).
  double SegmentDistance(const Eigen::Vector3f& p) const;
  // The root-to-tip unit tangent of the segment vertex nearest p within
  // `radius_mm` (the segments themselves, not the grid); false when none.
  bool NearestSegmentTangent(const Eigen::Vector3f& p, double radius_mm,
                             Eigen::Vector3f* tangent) const;
  bool Contains(const Eigen::Vector3f& p) const;

  Eigen::Vector3i size() const { return size_; }
  const Eigen::Vector3f& origin() const { return origin_; }
  double voxel_mm() const { return voxel_mm_; }

 private:
  struct SegmentIndex;
  static std::shared_ptr<const SegmentIndex> IndexSegments(
      const std::vector<StrandSegment>& segments);
  // channels: 3 (vectors) or 6 (tensor xx yy zz xy xz yz), voxel-major.
  Eigen::Vector3f Direction(const std::vector<float>& field, const Eigen::Vector3f& p,
                            const Eigen::Vector3f& previous) const;
  void Sample(const std::vector<float>& field, int channels, const Eigen::Vector3f& p,
              float* out) const;

  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  Eigen::Vector3i size_ = Eigen::Vector3i::Zero();
  double voxel_mm_ = 2;
  bool directed_ = true;
  std::vector<float> interior_, surface_, distance_, ribbon_distance_, segment_distance_;
  std::shared_ptr<const SegmentIndex> segment_index_;  // the segments' vertices and tangents
};

// The Laplace solve behind the fields: values in `fixed` voxels stay, the
// others become the discrete harmonic interpolant (6-neighbour stencil),
// solved coarse to fine with SOR sweeps at each level. `values` has
// `channels` floats per voxel, voxel index x + nx (y + ny z). Faces of the
// grid are Neumann (mirror) unless fixed.
void SolveLaplace(const Eigen::Vector3i& size, int channels, const std::vector<uint8_t>& fixed,
                  std::vector<float>* values, int sweeps_per_level);

}  // namespace hairrig
