#include "reconstruction/point_grid.h"

#include <algorithm>
#include <numeric>

namespace hairrig {

namespace {
constexpr int64_t kCellRange = int64_t{1} << 20;  // cells per axis that keys tell apart
}  // namespace

int64_t PointGrid::Key(int64_t x, int64_t y, int64_t z) {
  const auto wrap = [](int64_t c) { return ((c % kCellRange) + kCellRange) % kCellRange; };
  return (wrap(x) * kCellRange + wrap(y)) * kCellRange + wrap(z);
}

PointGrid::PointGrid(const std::vector<Eigen::Vector3f>& positions, double cell_mm)
    : positions_(positions), cell_mm_(cell_mm) {
  std::vector<int64_t> keys(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3f& p = positions[i];
    keys[i] = Key(CellOf(p.x()), CellOf(p.y()), CellOf(p.z()));
  }
  order_.resize(positions.size());
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(),
            [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
  sorted_.reserve(order_.size());
  for (const uint32_t i : order_) sorted_.push_back(positions[i]);
  for (uint32_t k = 0; k < order_.size();) {
    uint32_t end = k;
    while (end < order_.size() && keys[order_[end]] == keys[order_[k]]) ++end;
    cells_[keys[order_[k]]] = {k, end};
    k = end;
  }
}

int64_t PointGrid::Nearest(const Eigen::Vector3f& q, double radius_mm, double* distance2) const {
  int64_t best = -1;
  double best2 = radius_mm * radius_mm;
  ForEachWithin(q, radius_mm, [&](uint32_t i, double d2) {
    if (d2 <= best2) {
      best2 = d2;
      best = i;
    }
  });
  if (distance2 != nullptr) *distance2 = best2;
  return best;
}

}  // namespace hairrig
