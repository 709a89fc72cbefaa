#include "core/strands.h"

#include <cmath>
#include <cstdio>
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

namespace {

// A point's coordinates are finite and small enough that differences between points do not
// overflow.
Status CheckCoordinates(const Eigen::Vector3f& p, size_t strand, uint32_t vertex, size_t point) {
  for (int axis = 0; axis < 3; ++axis) {
    const float value = p[axis];
    if (std::isfinite(value) && std::abs(value) <= kMaxStrandCoordinateMm) continue;
    char what[160];
    if (std::isfinite(value))
      std::snprintf(what, sizeof what,
                    "%c = %.3g mm is beyond +-%.0e mm, where distances between points overflow",
                    "xyz"[axis], static_cast<double>(value),
                    static_cast<double>(kMaxStrandCoordinateMm));
    else
      std::snprintf(what, sizeof what, "%c is not finite (NaN or inf)", "xyz"[axis]);
    return CorruptData("strand " + std::to_string(strand) + " vertex " + std::to_string(vertex) +
                       " (point " + std::to_string(point) + "): " + what +
                       " (damaged data, or not millimetres)");
  }
  return Status::Ok();
}

}  // namespace

Status StrandSet::Check() const {
  size_t total = 0;
  for (size_t i = 0; i < point_counts.size(); ++i) {
    if (point_counts[i] == 0) return CorruptData("strand " + std::to_string(i) + " has no points");
    total += point_counts[i];
  }
  if (total != points_mm.size()) {
    return CorruptData("strand point counts add up to " + std::to_string(total) +
                       " but there are " + std::to_string(points_mm.size()) + " points");
  }
  size_t point = 0;
  for (size_t strand = 0; strand < point_counts.size(); ++strand) {
    for (uint32_t vertex = 0; vertex < point_counts[strand]; ++vertex, ++point)
      HR_RETURN_IF_ERROR(CheckCoordinates(points_mm[point], strand, vertex, point));
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
