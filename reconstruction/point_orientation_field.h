// The 3D orientation field of an oriented point cloud (Luo et al. 2013,
// Sec. 4 Eq. 2): at any position, the unit o maximising
// sum_q w_q rho_q (o . o_q)^2 over the points q within 2 sigma,
// w_q = exp(-|p - q|^2 / (2 sigma^2)), rho_q the point's confidence; the
// principal eigenvector of that structure tensor. Directions are unsigned.
// Units mm; any frame.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "reconstruction/point_cloud.h"
#include "reconstruction/point_grid.h"

namespace hairrig {

class PointOrientationField {
 public:
  // `points` must outlive the field and not change while it lives (it keeps
  // copies of their positions, directions and confidences). sigma_mm > 0.
  PointOrientationField(const std::vector<OrientedPoint>& points, double sigma_mm);
  // Not copied or moved: the grid refers to the field's own positions.
  PointOrientationField(const PointOrientationField&) = delete;
  PointOrientationField& operator=(const PointOrientationField&) = delete;

  // The orientation at p from the neighbours whose direction is within
  // acos(min_abs_cos) of `reference` (unsigned; Luo Sec. 5.1 keeps crossing
  // wisps apart this way), signed to agree with `reference`. A zero
  // reference uses every neighbour. False when fewer than `min_neighbours`
  // points qualify; *neighbours (optional) is their number either way.
  bool At(const Eigen::Vector3f& p, const Eigen::Vector3f& reference, double min_abs_cos,
          int min_neighbours, Eigen::Vector3f* orientation, int* neighbours = nullptr) const;

  const PointGrid& grid() const { return grid_; }
  const std::vector<OrientedPoint>& points() const { return points_; }
  double sigma_mm() const { return sigma_mm_; }

 private:
  const std::vector<OrientedPoint>& points_;
  std::vector<Eigen::Vector3f> positions_;
  double sigma_mm_;
  PointGrid grid_;
  // Per grid slot (PointGrid::ForEachSlotWithin): the point's direction and
  // max(confidence, 1e-3), read contiguously by At.
  std::vector<Eigen::Vector3f> slot_direction_;
  std::vector<float> slot_weight_;
};

// Every point's direction replaced by the field's at its position (Luo Eq. 2
// evaluated on the cloud itself), over the neighbours within acos(min_abs_cos)
// of the point's own direction (the point itself among them), so that
// crossing layers keep their own directions. Positions, confidences and
// views are unchanged. sigma_mm > 0; min_abs_cos in [0, 1).
std::vector<OrientedPoint> SmoothDirections(std::vector<OrientedPoint> points, double sigma_mm,
                                            double min_abs_cos, int threads);

}  // namespace hairrig
