// A uniform grid over a point set for radius queries (mm, any frame): a copy
// of the points sorted by cell (a query reads each cell's run contiguously),
// a hash from cell to its run. Built once (O(n log n)), then read by any
// number of threads.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace hairrig {

class PointGrid {
 public:
  // `positions` must outlive the grid and not change (queries read the
  // grid's sorted copy, positions() the caller's). cell_mm > 0; queries are cheapest
  // with radius <= cell_mm (27 cells visited).
  PointGrid(const std::vector<Eigen::Vector3f>& positions, double cell_mm);

  const std::vector<Eigen::Vector3f>& positions() const { return positions_; }
  double cell_mm() const { return cell_mm_; }

  // Calls visit(index, squared distance) for every point within `radius_mm`
  // of q (<=), in no particular order.
  template <typename Visit>
  void ForEachWithin(const Eigen::Vector3f& q, double radius_mm, Visit&& visit) const {
    const double radius2 = radius_mm * radius_mm;
    const int64_t reach = static_cast<int64_t>(std::ceil(radius_mm / cell_mm_));
    const int64_t cx = CellOf(q.x()), cy = CellOf(q.y()), cz = CellOf(q.z());
    for (int64_t dz = -reach; dz <= reach; ++dz)
      for (int64_t dy = -reach; dy <= reach; ++dy)
        for (int64_t dx = -reach; dx <= reach; ++dx) {
          const auto cell = cells_.find(Key(cx + dx, cy + dy, cz + dz));
          if (cell == cells_.end()) continue;
          for (uint32_t k = cell->second.first; k < cell->second.second; ++k) {
            const double d2 = (sorted_[k] - q).cast<double>().squaredNorm();
            if (d2 <= radius2) visit(order_[k], d2);
          }
        }
  }

  // Whether some point within `radius_mm` of q (<=) satisfies
  // accept(index, squared distance); stops at the first, looking in q's own
  // cell before the others.
  template <typename Accept>
  bool AnyWithin(const Eigen::Vector3f& q, double radius_mm, Accept&& accept) const {
    const double radius2 = radius_mm * radius_mm;
    const int64_t reach = static_cast<int64_t>(std::ceil(radius_mm / cell_mm_));
    const int64_t cx = CellOf(q.x()), cy = CellOf(q.y()), cz = CellOf(q.z());
    const auto any_in_cell = [&](int64_t x, int64_t y, int64_t z) {
      const auto cell = cells_.find(Key(x, y, z));
      if (cell == cells_.end()) return false;
      for (uint32_t k = cell->second.first; k < cell->second.second; ++k) {
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
  static int64_t Key(int64_t x, int64_t y, int64_t z);

  const std::vector<Eigen::Vector3f>& positions_;
  double cell_mm_;
  std::vector<uint32_t> order_;          // point indices sorted by cell
  std::vector<Eigen::Vector3f> sorted_;  // positions_[order_[k]]
  std::unordered_map<int64_t, std::pair<uint32_t, uint32_t>>
      cells_;  // cell -> [begin, end) in order_ and sorted_
};

}  // namespace hairrig
