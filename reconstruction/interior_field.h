// The interior field I of Luo et al. 2013 Sec. 7.1: a level set field on a
// regular grid that rises smoothly from 0 on the scalp to 1 at the captured
// hair points. Voxels holding a point are fixed to 1; voxels inside the head
// or on its scalp to 0 (the paper fixes the scalp's; fixing the head's
// interior as well makes the field rise away from the head everywhere); the
// rest is the harmonic interpolant (hybrid_field.h's SolveLaplace), so I
// stays 1 beyond the hair and grad I points from the scalp out into the hair.
// Units mm, the points' frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "reconstruction/point_cloud.h"

namespace hairrig {

struct InteriorFieldOptions {
  double voxel_mm = 4.0;
  double margin_mm = 20;      // around the points' and the head's bounds
  int sweeps_per_level = 40;  // SolveLaplace's SOR sweeps per level

  Status Check() const;
};

class InteriorField {
 public:
  // InvalidArgument for no points, bad options or a grid of more than 64
  // million voxels.
  static Result<InteriorField> Build(const std::vector<OrientedPoint>& points,
                                     const HeadModel& head, const InteriorFieldOptions& options);

  // Trilinear, in [0, 1]; outside the grid the nearest face's value.
  double At(const Eigen::Vector3f& p) const;
  // Central differences over one voxel (per mm).
  Eigen::Vector3f Gradient(const Eigen::Vector3f& p) const;

  Eigen::Vector3i size() const { return size_; }
  double voxel_mm() const { return voxel_mm_; }

 private:
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  Eigen::Vector3i size_ = Eigen::Vector3i::Zero();
  double voxel_mm_ = 4;
  std::vector<float> values_;  // index x + nx (y + ny z)
};

}  // namespace hairrig
