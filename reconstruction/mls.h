// Moving least squares on a point cloud (Levin 1998), as Luo et al. 2013
// Sec. 4 filter their PMVS points ("for each point, we fit an optimal plane to
// the locally-weighted neighbors ... sigma of 2 mm") and project grown strand
// vertices onto the point set surface (Sec. 5.1).
//
// The plane at a query point q: the centroid and the smallest principal axis
// of its neighbours weighted by exp(-|p - q|^2 / sigma^2), neighbours within
// 2 sigma. Units mm; any frame.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "reconstruction/point_cloud.h"
#include "reconstruction/point_grid.h"

namespace hairrig {

class PointSetSurface {
 public:
  // `positions` must outlive the surface. sigma_mm > 0.
  PointSetSurface(const std::vector<Eigen::Vector3f>& positions, double sigma_mm);
  // Over a grid already built on the points (any cell size; it must outlive
  // the surface), so a caller that has one does not build a second.
  PointSetSurface(const PointGrid& grid, double sigma_mm);

  // The plane through q's weighted neighbourhood: q projected onto it and its
  // unit normal. False where fewer than `min_neighbours` points are within
  // 2 sigma (no surface there).
  bool Project(const Eigen::Vector3f& q, Eigen::Vector3f* projected, Eigen::Vector3f* normal,
               int min_neighbours = 4) const;

 private:
  double sigma_mm_;
  std::unique_ptr<PointGrid> owned_grid_;  // built by the positions' constructor
  const PointGrid& grid_;
};

// Every point moved onto its MLS plane and its direction projected into the
// plane (renormalised; kept where the projection degenerates). Points with
// too few neighbours are kept as they are.
std::vector<OrientedPoint> SmoothByMls(const std::vector<OrientedPoint>& points, double sigma_mm,
                                       int threads);

}  // namespace hairrig
