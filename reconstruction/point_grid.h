// A uniform grid over a point set for radius queries (mm, any frame): a copy
// of the points sorted by cell (a query reads each cell's run contiguously)
// and, per cell, its run: an array over the points' box of cells where that
// box is small (a few cells per point; O(n) to build), else a hash
// (O(n log n)). Built once, then read by any number of threads.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace hairrig {

class PointGrid {
 public:
  // `positions` must outlive the grid and not change (queries read the
  // grid's sorted copy, positions() the caller's). cell_mm > 0; a query visits the
  // cells its sphere reaches (27 at most with radius <= cell_mm).
  PointGrid(const std::vector<Eigen::Vector3f>& positions, double cell_mm);

  const std::vector<Eigen::Vector3f>& positions() const { return positions_; }
  double cell_mm() const { return cell_mm_; }

  // Calls visit(index, squared distance) for every point within `radius_mm`
  // of q (<=), in no particular order.
  template <typename Visit>
  void ForEachWithin(const Eigen::Vector3f& q, double radius_mm, Visit&& visit) const {
    ForEachSlotWithin(q, radius_mm, [&](uint32_t slot, double d2) { visit(order_[slot], d2); });
  }

  // As ForEachWithin, but visit(slot, squared distance) gets the point's slot
  // in the grid's cell order (order()[slot] is its index): a caller that keeps
  // per-point data in slot order reads it contiguously, cell by cell.
  template <typename Visit>
  void ForEachSlotWithin(const Eigen::Vector3f& q, double radius_mm, Visit&& visit) const {
    const double radius2 = radius_mm * radius_mm;
    const double cull2 = radius2 * (1 + 1e-6);  // rounding slack: never cull a point within reach
    const int64_t reach = static_cast<int64_t>(std::ceil(radius_mm / cell_mm_));
    const int64_t cx = CellOf(q.x()), cy = CellOf(q.y()), cz = CellOf(q.z());
    const auto visit_range = [&](std::pair<uint32_t, uint32_t> range) {
      for (uint32_t k = range.first; k < range.second; ++k) {
        const double d2 = (sorted_[k] - q).cast<double>().squaredNorm();
        if (d2 <= radius2) visit(k, d2);
      }
    };
    // Rows of cells along x whose box lies wholly beyond the radius are skipped.
    for (int64_t dz = -reach; dz <= reach; ++dz) {
      const double gz2 = Gap2(q.z(), cz, dz);
      if (gz2 > cull2) continue;
      for (int64_t dy = -reach; dy <= reach; ++dy) {
        if (gz2 + Gap2(q.y(), cy, dy) > cull2) continue;
        if (dense()) {
          visit_range(RowRange(cx - reach, cx + reach, cy + dy, cz + dz));
        } else {
          for (int64_t dx = -reach; dx <= reach; ++dx)
            visit_range(CellRange(cx + dx, cy + dy, cz + dz));
        }
      }
    }
  }

  // The points' indices in slot order (see ForEachSlotWithin).
  const std::vector<uint32_t>& order() const { return order_; }
  // The positions in slot order: slot_positions()[slot] == positions()[order()[slot]].
  const std::vector<Eigen::Vector3f>& slot_positions() const { return sorted_; }

  // Whether some point within `radius_mm` of q (<=) satisfies
  // accept(index, squared distance); stops at the first, looking in q's own
  // cell before the others.
  template <typename Accept>
  bool AnyWithin(const Eigen::Vector3f& q, double radius_mm, Accept&& accept) const {
    const double radius2 = radius_mm * radius_mm;
    const int64_t reach = static_cast<int64_t>(std::ceil(radius_mm / cell_mm_));
    const int64_t cx = CellOf(q.x()), cy = CellOf(q.y()), cz = CellOf(q.z());
    const auto any_in_cell = [&](int64_t x, int64_t y, int64_t z) {
      const std::pair<uint32_t, uint32_t> cell = CellRange(x, y, z);
      for (uint32_t k = cell.first; k < cell.second; ++k) {
        const double d2 = (sorted_[k] - q).cast<double>().squaredNorm();
        if (d2 <= radius2 && accept(order_[k], d2)) return true;
      }
      return false;
    };
    if (any_in_cell(cx, cy, cz)) return true;
    for (int64_t dz = -reach; dz <= reach; ++dz)
      for (int64_t dy = -reach; dy <= reach; ++dy)
        for (int64_t dx = -reach; dx <= reach; ++dx) {
          if ((dx != 0 || dy != 0 || dz != 0) && any_in_cell(cx + dx, cy + dy, cz + dz))
            return true;
        }
    return false;
  }

  // The nearest point within `radius_mm` (-1 when none) and its squared distance.
  int64_t Nearest(const Eigen::Vector3f& q, double radius_mm, double* distance2 = nullptr) const;

 private:
  int64_t CellOf(float v) const { return static_cast<int64_t>(std::floor(v / cell_mm_)); }
  // The squared distance along one axis from coordinate v (in cell c) to the
  // cell c + d: 0 for its own cell.
  double Gap2(float v, int64_t c, int64_t d) const {
    if (d == 0) return 0;
    const double gap = d > 0 ? static_cast<double>(c + d) * cell_mm_ - v
                             : v - static_cast<double>(c + d + 1) * cell_mm_;
    return gap > 0 ? gap * gap : 0;
  }
  static int64_t Key(int64_t x, int64_t y, int64_t z);
  bool dense() const { return !dense_start_.empty(); }
  // The slots [begin, end) of one cell; of the cells x0..x1 of one row (dense only).
  std::pair<uint32_t, uint32_t> CellRange(int64_t x, int64_t y, int64_t z) const;
  std::pair<uint32_t, uint32_t> RowRange(int64_t x0, int64_t x1, int64_t y, int64_t z) const {
    if (y < low_[1] || y >= low_[1] + size_[1] || z < low_[2] || z >= low_[2] + size_[2])
      return {0, 0};
    x0 = std::max(x0, low_[0]), x1 = std::min(x1, low_[0] + size_[0] - 1);
    if (x0 > x1) return {0, 0};
    const int64_t row = ((z - low_[2]) * size_[1] + (y - low_[1])) * size_[0] - low_[0];
    return {dense_start_[static_cast<size_t>(row + x0)],
            dense_start_[static_cast<size_t>(row + x1 + 1)]};
  }
  void BuildDense(const std::vector<int64_t>& cell_x, const std::vector<int64_t>& cell_y,
                  const std::vector<int64_t>& cell_z);
  void BuildHashed(const std::vector<int64_t>& cell_x, const std::vector<int64_t>& cell_y,
                   const std::vector<int64_t>& cell_z);

  const std::vector<Eigen::Vector3f>& positions_;
  double cell_mm_;
  std::vector<uint32_t> order_;          // point indices sorted by cell
  std::vector<Eigen::Vector3f> sorted_;  // positions_[order_[k]]
  // Where the points' cells span a box of at most a few cells per point, the
  // cells are an array over that box (x fastest), dense_start_[cell] the
  // cell's first slot (one past the last at the end), so a row of cells is
  // one run of slots; otherwise a hash from cell to its run.
  int64_t low_[3] = {0, 0, 0}, size_[3] = {0, 0, 0};
  std::vector<uint32_t> dense_start_;
  std::unordered_map<int64_t, std::pair<uint32_t, uint32_t>>
      cells_;  // cell -> [begin, end) in order_ and sorted_
};

}  // namespace hairrig
