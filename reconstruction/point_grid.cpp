#include "reconstruction/point_grid.h"

#include <algorithm>
#include <cmath>
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
  const size_t n = positions.size();
  std::vector<int64_t> cell_x(n), cell_y(n), cell_z(n);
  int64_t low[3] = {0, 0, 0}, high[3] = {-1, -1, -1};
  for (size_t i = 0; i < n; ++i) {
    const int64_t c[3] = {CellOf(positions[i].x()), CellOf(positions[i].y()),
                          CellOf(positions[i].z())};
    cell_x[i] = c[0], cell_y[i] = c[1], cell_z[i] = c[2];
    for (int a = 0; a < 3; ++a) {
      low[a] = i == 0 ? c[a] : std::min(low[a], c[a]);
      high[a] = i == 0 ? c[a] : std::max(high[a], c[a]);
    }
  }
  // A dense array of cells costs 4 bytes a cell: used while that stays
  // within a few times the points' own storage (spans in double: a far
  // point must not overflow them).
  double cells = 1;
  for (int a = 0; a < 3; ++a)
    cells *= static_cast<double>(high[a]) - static_cast<double>(low[a]) + 1;
  if (n > 0 && std::isfinite(cells) && cells <= std::max(65536.0, 4.0 * static_cast<double>(n)) &&
      cells < 2e9) {
    for (int a = 0; a < 3; ++a) low_[a] = low[a], size_[a] = high[a] - low[a] + 1;
    BuildDense(cell_x, cell_y, cell_z);
  } else {
    BuildHashed(cell_x, cell_y, cell_z);
  }
  sorted_.reserve(order_.size());
  for (const uint32_t i : order_) sorted_.push_back(positions[i]);
}

void PointGrid::BuildDense(const std::vector<int64_t>& cell_x, const std::vector<int64_t>& cell_y,
                           const std::vector<int64_t>& cell_z) {
  const size_t n = cell_x.size();
  const size_t cells = static_cast<size_t>(size_[0] * size_[1] * size_[2]);
  std::vector<uint32_t> index(n);
  dense_start_.assign(cells + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    index[i] = static_cast<uint32_t>(((cell_z[i] - low_[2]) * size_[1] + (cell_y[i] - low_[1])) *
                                         size_[0] +
                                     (cell_x[i] - low_[0]));
    ++dense_start_[index[i] + 1];
  }
  for (size_t c = 0; c < cells; ++c) dense_start_[c + 1] += dense_start_[c];
  std::vector<uint32_t> fill(dense_start_.begin(), dense_start_.end() - 1);
  order_.resize(n);
  for (size_t i = 0; i < n; ++i) order_[fill[index[i]]++] = static_cast<uint32_t>(i);
}

void PointGrid::BuildHashed(const std::vector<int64_t>& cell_x, const std::vector<int64_t>& cell_y,
                            const std::vector<int64_t>& cell_z) {
  const size_t n = cell_x.size();
  std::vector<int64_t> keys(n);
  for (size_t i = 0; i < n; ++i) keys[i] = Key(cell_x[i], cell_y[i], cell_z[i]);
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(),
            [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
  for (uint32_t k = 0; k < order_.size();) {
    uint32_t end = k;
    while (end < order_.size() && keys[order_[end]] == keys[order_[k]]) ++end;
    cells_[keys[order_[k]]] = {k, end};
    k = end;
  }
}

std::pair<uint32_t, uint32_t> PointGrid::CellRange(int64_t x, int64_t y, int64_t z) const {
  if (dense()) return RowRange(x, x, y, z);
  const auto cell = cells_.find(Key(x, y, z));
  return cell == cells_.end() ? std::pair<uint32_t, uint32_t>{0, 0} : cell->second;
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
