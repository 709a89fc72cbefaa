#include "reconstruction/voxel_cache.h"

#include <cstddef>
#include <utility>

namespace hairrig {

namespace {
size_t CellCount(const Eigen::Vector3i& size) {
  return static_cast<size_t>(size.x()) * static_cast<size_t>(size.y()) *
         static_cast<size_t>(size.z());
}
}  // namespace

VoxelCache::VoxelCache(Question question, const Eigen::Vector3f& origin_mm,
                       const Eigen::Vector3i& size, double cell_mm)
    : question_(std::move(question)),
      origin_mm_(origin_mm),
      size_(size.cwiseMax(0)),
      cell_mm_(static_cast<float>(cell_mm)),
      cells_(new std::atomic<uint8_t>[CellCount(size_)]) {
  for (size_t i = 0; i < CellCount(size_); ++i)
    cells_[i].store(kUnknown, std::memory_order_relaxed);
}

bool VoxelCache::operator()(const Eigen::Vector3f& p_mm) const {
  const Eigen::Vector3f u = (p_mm - origin_mm_) / cell_mm_ + Eigen::Vector3f::Constant(0.5f);
  if (!(u.allFinite() && (u.array() >= 0).all() && (u.array() < size_.cast<float>().array()).all()))
    return question_(p_mm);
  const Eigen::Vector3i c = u.array().floor().cast<int>();
  std::atomic<uint8_t>& cell =
      cells_[c.x() +
             static_cast<int64_t>(size_.x()) * (c.y() + static_cast<int64_t>(size_.y()) * c.z())];
  uint8_t known = cell.load(std::memory_order_relaxed);
  if (known == kUnknown) {
    const Eigen::Vector3f centre = origin_mm_ + c.cast<float>() * cell_mm_;
    known = question_(centre) ? kYes : kNo;
    cell.store(known, std::memory_order_relaxed);
  }
  return known == kYes;
}

}  // namespace hairrig
