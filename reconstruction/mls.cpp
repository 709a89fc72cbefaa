#include "reconstruction/mls.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Eigenvalues>

#include "core/parallel.h"

namespace hairrig {

namespace {
constexpr int64_t kCellRange = int64_t{1} << 20;  // cells per axis that keys tell apart

int64_t CellOf(float v, double cell_mm) { return static_cast<int64_t>(std::floor(v / cell_mm)); }
}  // namespace

int64_t PointSetSurface::Key(int64_t x, int64_t y, int64_t z) const {
  const auto wrap = [](int64_t c) { return ((c % kCellRange) + kCellRange) % kCellRange; };
  return (wrap(x) * kCellRange + wrap(y)) * kCellRange + wrap(z);
}

PointSetSurface::PointSetSurface(const std::vector<Eigen::Vector3f>& positions, double sigma_mm)
    : positions_(positions), sigma_mm_(sigma_mm), cell_mm_(2 * sigma_mm) {
  std::vector<int64_t> keys(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3f& p = positions[i];
    keys[i] = Key(CellOf(p.x(), cell_mm_), CellOf(p.y(), cell_mm_), CellOf(p.z(), cell_mm_));
  }
  order_.resize(positions.size());
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
  for (uint32_t k = 0; k < order_.size();) {
    uint32_t end = k;
    while (end < order_.size() && keys[order_[end]] == keys[order_[k]]) ++end;
    cells_[keys[order_[k]]] = {k, end};
    k = end;
  }
}

bool PointSetSurface::Project(const Eigen::Vector3f& q, Eigen::Vector3f* projected, Eigen::Vector3f* normal,
                              int min_neighbours) const {
  const double radius2 = 4 * sigma_mm_ * sigma_mm_;
  const double inv_sigma2 = 1.0 / (sigma_mm_ * sigma_mm_);
  const int64_t cx = CellOf(q.x(), cell_mm_), cy = CellOf(q.y(), cell_mm_), cz = CellOf(q.z(), cell_mm_);
  double weight = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0;
  const Eigen::Vector3d origin = q.cast<double>();
  for (int64_t dz = -1; dz <= 1; ++dz)
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const auto cell = cells_.find(Key(cx + dx, cy + dy, cz + dz));
        if (cell == cells_.end()) continue;
        for (uint32_t k = cell->second.first; k < cell->second.second; ++k) {
          const Eigen::Vector3d d = positions_[order_[k]].cast<double>() - origin;
          const double d2 = d.squaredNorm();
          if (d2 > radius2) continue;
          const double w = std::exp(-d2 * inv_sigma2);
          weight += w;
          sum += w * d;
          outer += w * d * d.transpose();
          ++count;
        }
      }
  if (count < min_neighbours || weight <= 0) return false;
  const Eigen::Vector3d mean = sum / weight;
  const Eigen::Matrix3d covariance = outer / weight - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Eigen::Vector3d n = eigen.eigenvectors().col(0);  // the smallest eigenvalue's
  // q is at 0 in these coordinates: move it along n onto the plane through mean.
  *projected = (origin + mean.dot(n) * n).cast<float>();
  *normal = n.cast<float>();
  return true;
}

std::vector<OrientedPoint> SmoothByMls(const std::vector<OrientedPoint>& points, double sigma_mm, int threads) {
  std::vector<Eigen::Vector3f> positions(points.size());
  for (size_t i = 0; i < points.size(); ++i) positions[i] = points[i].position_mm;
  const PointSetSurface surface(positions, sigma_mm);
  std::vector<OrientedPoint> out = points;
  ParallelFor(points.size(), threads, [&] {
    return [&](size_t i) {
      Eigen::Vector3f projected, normal;
      if (!surface.Project(points[i].position_mm, &projected, &normal)) return;
      out[i].position_mm = projected;
      const Eigen::Vector3f in_plane = points[i].direction - points[i].direction.dot(normal) * normal;
      if (in_plane.norm() > 1e-3f) out[i].direction = in_plane.normalized();
    };
  });
  return out;
}

}  // namespace hairrig
