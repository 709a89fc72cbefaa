// A yes-or-no question about positions answered once per cell of a regular
// grid, at the cell's centre, for hot loops such as strand growth (a strand's
// every step asks), where the question itself is costly (projecting into
// every view). Cell c is centred at origin_mm + c * cell_mm, c in [0, size);
// a position outside the cells is answered exactly. Thread-safe: concurrent callers may answer
// one cell twice, with the same answer, as long as the question is a pure
// function of the position.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>

namespace hairrig {

class VoxelCache {
 public:
  using Question = std::function<bool(const Eigen::Vector3f& p_mm)>;
  VoxelCache(Question question, const Eigen::Vector3f& origin_mm, const Eigen::Vector3i& size,
             double cell_mm);
  bool operator()(const Eigen::Vector3f& p_mm) const;

 private:
  enum : uint8_t { kUnknown = 0, kNo = 1, kYes = 2 };
  Question question_;
  Eigen::Vector3f origin_mm_;
  Eigen::Vector3i size_;
  float cell_mm_;
  std::unique_ptr<std::atomic<uint8_t>[]> cells_;
};

}  // namespace hairrig
