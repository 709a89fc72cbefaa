#include "reconstruction/mls.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "reconstruction/symmetric_outer_sum.h"

namespace hairrig {

PointSetSurface::PointSetSurface(const std::vector<Eigen::Vector3f>& positions, double sigma_mm)
    : sigma_mm_(sigma_mm),
      owned_grid_(std::make_unique<PointGrid>(positions, 2 * sigma_mm)),
      grid_(*owned_grid_) {}

PointSetSurface::PointSetSurface(const PointGrid& grid, double sigma_mm)
    : sigma_mm_(sigma_mm), grid_(grid) {}

bool PointSetSurface::Project(const Eigen::Vector3f& q, Eigen::Vector3f* projected,
                              Eigen::Vector3f* normal, int min_neighbours) const {
  const double inv_sigma2 = 1.0 / (sigma_mm_ * sigma_mm_);
  double weight = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  SymmetricOuterSum outer;  // the second moments
  int count = 0;
  const Eigen::Vector3d origin = q.cast<double>();
  const std::vector<Eigen::Vector3f>& positions = grid_.slot_positions();
  grid_.ForEachSlotWithin(q, 2 * sigma_mm_, [&](uint32_t slot, double d2) {
    const Eigen::Vector3d d = positions[slot].cast<double>() - origin;
    const double w = std::exp(-d2 * inv_sigma2);
    weight += w;
    const Eigen::Vector3d wd = w * d;
    sum += wd;
    outer.Add(wd, d);
    ++count;
  });
  if (count < min_neighbours || weight <= 0) return false;
  const Eigen::Vector3d mean = sum / weight;
  const Eigen::Matrix3d covariance = outer.Matrix() / weight - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Eigen::Vector3d n = eigen.eigenvectors().col(0);  // the smallest eigenvalue's
  // q is at 0 in these coordinates: move it along n onto the plane through mean.
  *projected = (origin + mean.dot(n) * n).cast<float>();
  *normal = n.cast<float>();
  return true;
}

std::vector<OrientedPoint> SmoothByMls(const std::vector<OrientedPoint>& points, double sigma_mm,
                                       int threads) {
  std::vector<Eigen::Vector3f> positions(points.size());
  for (size_t i = 0; i < points.size(); ++i) positions[i] = points[i].position_mm;
  const PointSetSurface surface(positions, sigma_mm);
  std::vector<OrientedPoint> out = points;
  ParallelFor(points.size(), threads, [&] {
    return [&](size_t i) {
      Eigen::Vector3f projected, normal;
      if (!surface.Project(points[i].position_mm, &projected, &normal)) return;
      out[i].position_mm = projected;
      const Eigen::Vector3f in_plane =
          points[i].direction - points[i].direction.dot(normal) * normal;
      if (in_plane.norm() > 1e-3f) out[i].direction = in_plane.normalized();
    };
  });
  return out;
}

}  // namespace hairrig
