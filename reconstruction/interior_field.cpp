#include "reconstruction/interior_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "reconstruction/central_gradient.h"
#include "reconstruction/hybrid_field.h"

namespace hairrig {

namespace {

constexpr int64_t kMaxVoxels = int64_t{64} << 20;

}  // namespace

Status InteriorFieldOptions::Check() const {
  if (!(voxel_mm > 0)) return InvalidArgument("interior field voxel_mm must be positive");
  if (!(margin_mm >= 0)) return InvalidArgument("interior field margin_mm must be non-negative");
  if (sweeps_per_level < 1)
    return InvalidArgument("interior field sweeps_per_level must be at least 1");
  return Status::Ok();
}

Result<InteriorField> InteriorField::Build(const std::vector<OrientedPoint>& points,
                                           const HeadModel& head, const InteriorFieldOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  if (points.empty()) return InvalidArgument("the interior field needs at least one point");
  Eigen::Vector3f lo = head.mesh().MinCorner().cast<float>(),
                  hi = head.mesh().MaxCorner().cast<float>();
  for (const OrientedPoint& p : points)
    lo = lo.cwiseMin(p.position_mm), hi = hi.cwiseMax(p.position_mm);
  InteriorField f;
  f.voxel_mm_ = o.voxel_mm;
  const float voxel = static_cast<float>(o.voxel_mm);
  f.origin_ = lo.array() - static_cast<float>(o.margin_mm);
  const Eigen::Vector3f extent = (hi - lo).array() + static_cast<float>(2 * o.margin_mm);
  f.size_ = (extent / voxel).array().ceil().cast<int>() + 1;
  const int64_t count = static_cast<int64_t>(f.size_.x()) * f.size_.y() * f.size_.z();
  if (count > kMaxVoxels) {
    return InvalidArgument(
        "the interior field's grid would have " + std::to_string(count) +
        " voxels; the points span too much space (are they in mm?) or voxel_mm is too small");
  }
  const auto index = [&](int x, int y, int z) {
    return x + static_cast<int64_t>(f.size_.x()) * (y + static_cast<int64_t>(f.size_.y()) * z);
  };
  f.values_.assign(static_cast<size_t>(count), 0.0f);
  std::vector<uint8_t> fixed(static_cast<size_t>(count), 0),
      head_voxel(static_cast<size_t>(count), 0);
  const double half_diagonal = 0.5 * std::sqrt(3.0) * o.voxel_mm;
  for (int z = 0; z < f.size_.z(); ++z)
    for (int y = 0; y < f.size_.y(); ++y)
      for (int x = 0; x < f.size_.x(); ++x) {
        const Eigen::Vector3d c =
            (f.origin_ + voxel * Eigen::Vector3i(x, y, z).cast<float>()).cast<double>();
        const double d = head.SignedDistance(c, nullptr);
        if (d < 0 || (d < half_diagonal && head.OnScalp(c))) head_voxel[index(x, y, z)] = 1;
      }
  for (const OrientedPoint& p : points) {
    const Eigen::Vector3i v = ((p.position_mm - f.origin_) / voxel).array().round().cast<int>();
    const int64_t i =
        index(std::clamp(v.x(), 0, f.size_.x() - 1), std::clamp(v.y(), 0, f.size_.y() - 1),
              std::clamp(v.z(), 0, f.size_.z() - 1));
    if (!head_voxel[i]) f.values_[i] = 1.0f, fixed[i] = 1;
  }
  for (int64_t i = 0; i < count; ++i)
    if (head_voxel[i]) fixed[i] = 1;  // value 0
  SolveLaplace(f.size_, 1, fixed, &f.values_, o.sweeps_per_level);
  return f;
}

double InteriorField::At(const Eigen::Vector3f& p) const {
  const Eigen::Vector3f g = (p - origin_) / static_cast<float>(voxel_mm_);
  int corner[3];
  float fraction[3];
  for (int k = 0; k < 3; ++k) {
    const float clamped = std::clamp(g[k], 0.0f, static_cast<float>(size_[k] - 1));
    corner[k] = std::min(static_cast<int>(clamped), std::max(size_[k] - 2, 0));
    fraction[k] = size_[k] > 1 ? clamped - static_cast<float>(corner[k]) : 0.0f;
  }
  const auto at = [&](int dx, int dy, int dz) {
    const int x = std::min(corner[0] + dx, size_.x() - 1),
              y = std::min(corner[1] + dy, size_.y() - 1);
    const int z = std::min(corner[2] + dz, size_.z() - 1);
    return static_cast<double>(
        values_[x + static_cast<size_t>(size_.x()) * (y + static_cast<size_t>(size_.y()) * z)]);
  };
  double value = 0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const double w = (dx ? fraction[0] : 1 - fraction[0]) *
                         (dy ? fraction[1] : 1 - fraction[1]) *
                         (dz ? fraction[2] : 1 - fraction[2]);
        value += w * at(dx, dy, dz);
      }
  return value;
}

Eigen::Vector3f InteriorField::Gradient(const Eigen::Vector3f& p) const {
  return CentralGradient([this](const Eigen::Vector3f& q) { return At(q); }, p,
                         static_cast<float>(voxel_mm_));
}

}  // namespace hairrig
