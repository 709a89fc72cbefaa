#include "core/strands.h"

#include <string>

namespace hairrig {

std::vector<size_t> StrandSet::Offsets() const {
  std::vector<size_t> offsets(point_counts.size() + 1, 0);
  for (size_t i = 0; i < point_counts.size(); ++i) offsets[i + 1] = offsets[i] + point_counts[i];
  return offsets;
}

void StrandSet::AddStrand(const std::vector<Eigen::Vector3f>& points) {
  points_mm.insert(points_mm.end(), points.begin(), points.end());
  point_counts.push_back(static_cast<uint32_t>(points.size()));
}

Status StrandSet::Validate() const {
  size_t total = 0;
  for (size_t i = 0; i < point_counts.size(); ++i) {
    if (point_counts[i] == 0) return CorruptData("strand " + std::to_string(i) + " has no points");
    total += point_counts[i];
  }
  if (total != points_mm.size()) {
    return CorruptData("strand point counts add up to " + std::to_string(total) + " but there are " +
                       std::to_string(points_mm.size()) + " points");
  }
  for (size_t i = 0; i < points_mm.size(); ++i) {
    if (!points_mm[i].allFinite()) return CorruptData("point " + std::to_string(i) + " is not finite (NaN or inf)");
  }
  if (!colors.empty() && colors.size() != points_mm.size()) {
    return CorruptData("there are " + std::to_string(colors.size()) + " colours for " +
                       std::to_string(points_mm.size()) + " points");
  }
  return Status::Ok();
}

std::vector<double> StrandSet::StrandLengths() const {
  std::vector<double> lengths(point_counts.size(), 0.0);
  size_t p = 0;
  for (size_t s = 0; s < point_counts.size(); ++s) {
    for (uint32_t k = 0; k < point_counts[s]; ++k, ++p) {
      if (k > 0) lengths[s] += static_cast<double>((points_mm[p] - points_mm[p - 1]).norm());
    }
  }
  return lengths;
}

}  // namespace hairrig
