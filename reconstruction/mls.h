// Moving least squares on a point cloud (Levin 1998), as Luo et al. 2013
// Sec. 4 filter their PMVS points ("for each point, we fit an optimal plane to
// the locally-weighted neighbors ... sigma of 2 mm") and project grown strand
// vertices onto the point set surface (Sec. 5.1).
//
// The plane at a query point q: the centroid and the smallest principal axis
// of its neighbours weighted by exp(-|p - q|^2 / sigma^2), neighbours within
// 2 sigma. Units mm; any frame.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "reconstruction/point_cloud.h"

namespace hairrig {

class PointSetSurface {
 public:
  // `positions` must outlive the surface. sigma_mm > 0.
  PointSetSurface(const std::vector<Eigen::Vector3f>& positions, double sigma_mm);

  // The plane through q's weighted neighbourhood: q projected onto it and its
  // unit normal. False where fewer than `min_neighbours` points are within
  // 2 sigma (no surface there).
  bool Project(const Eigen::Vector3f& q, Eigen::Vector3f* projected, Eigen::Vector3f* normal,
               int min_neighbours = 4) const;

 private:
  int64_t Key(int64_t x, int64_t y, int64_t z) const;
  const std::vector<Eigen::Vector3f>& positions_;
  double sigma_mm_, cell_mm_;
  std::vector<uint32_t> order_;                                   // point indices sorted by cell
  std::unordered_map<int64_t, std::pair<uint32_t, uint32_t>> cells_;  // cell -> [begin, end) in order_
};

// Every point moved onto its MLS plane and its direction projected into the
// plane (renormalised; kept where the projection degenerates). Points with
// too few neighbours are kept as they are.
std::vector<OrientedPoint> SmoothByMls(const std::vector<OrientedPoint>& points, double sigma_mm, int threads);

}  // namespace hairrig
