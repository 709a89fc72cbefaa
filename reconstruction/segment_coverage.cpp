#include "reconstruction/segment_coverage.h"

#include <cmath>

namespace hairrig {

Eigen::Vector3f PolylineTangent(const Eigen::Vector3f* points, size_t count, size_t i) {
  if (count < 2) return Eigen::Vector3f::Zero();
  const size_t before = i > 0 ? i - 1 : 0, after = i + 1 < count ? i + 1 : count - 1;
  const Eigen::Vector3f d = points[after] - points[before];
  const float n = d.norm();
  return n > 0 ? Eigen::Vector3f(d / n) : Eigen::Vector3f::Zero();
}

StrandCoverage::StrandCoverage(const CoverageOptions& options)
    : radius_mm_(options.radius_mm), min_cos_(std::cos(options.max_angle_deg * M_PI / 180.0)) {}

int64_t StrandCoverage::CellKey(const Eigen::Vector3f& p) const {
  // 21 bits a coordinate: cells of radius_mm over +-1e6 cells, far beyond a head.
  const auto cell = [&](float v) {
    return (static_cast<int64_t>(std::floor(v / radius_mm_)) + (1 << 20)) & ((1 << 21) - 1);
  };
  return cell(p.x()) | (cell(p.y()) << 21) | (cell(p.z()) << 42);
}

void StrandCoverage::Add(const Eigen::Vector3f* points, size_t count) {
  for (size_t i = 0; i < count; ++i)
    cells_[CellKey(points[i])].push_back(
        {points[i], PolylineTangent(points, count, i), {strands_, static_cast<int>(i)}});
  ++strands_;
}

template <typename Visit>
void StrandCoverage::ForEachNear(const Eigen::Vector3f& p, double radius_mm, Visit&& visit) const {
  const float r = static_cast<float>(radius_mm_);
  const int reach = static_cast<int>(std::ceil(radius_mm / radius_mm_));
  for (int dz = -reach; dz <= reach; ++dz)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const Eigen::Vector3f q =
            p + r * Eigen::Vector3f(static_cast<float>(dx), static_cast<float>(dy),
                                    static_cast<float>(dz));
        const auto cell = cells_.find(CellKey(q));
        if (cell == cells_.end()) continue;
        for (const Entry& e : cell->second)
          if (visit(e)) return;
      }
}

void StrandCoverage::Add(const std::vector<Eigen::Vector3f>& strand) {
  Add(strand.data(), strand.size());
}

void StrandCoverage::Add(const StrandSet& strands) {
  const std::vector<size_t> offsets = strands.Offsets();
  for (size_t s = 0; s < strands.num_strands(); ++s)
    Add(strands.points_mm.data() + offsets[s], offsets[s + 1] - offsets[s]);
}

bool StrandCoverage::Covers(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent) const {
  // Any vertex within reach will do: the first one found ends the search.
  const float radius2 = static_cast<float>(radius_mm_ * radius_mm_);
  bool covered = false;
  ForEachNear(p, radius_mm_, [&](const Entry& e) {
    covered = (e.position - p).squaredNorm() <= radius2 && e.tangent.dot(tangent) >= min_cos_;
    return covered;
  });
  return covered;
}

StrandCoverage::Vertex StrandCoverage::Nearest(const Eigen::Vector3f& p,
                                               const Eigen::Vector3f& tangent, double radius_mm,
                                               double min_cos) const {
  float best2 = static_cast<float>(radius_mm * radius_mm);
  Vertex best;
  ForEachNear(p, radius_mm, [&](const Entry& e) {
    const float d2 = (e.position - p).squaredNorm();
    if (d2 <= best2 && e.tangent.dot(tangent) >= min_cos) best2 = d2, best = e.where;
    return false;
  });
  return best;
}

double StrandCoverage::UncoveredLengthMm(const StrandSegment& segment) const {
  const std::vector<Eigen::Vector3f>& v = segment.points_mm;
  std::vector<char> uncovered(v.size());
  for (size_t i = 0; i < v.size(); ++i)
    uncovered[i] = !Covers(v[i], PolylineTangent(v.data(), v.size(), i));
  double length = 0;
  for (size_t i = 1; i < v.size(); ++i)
    length += 0.5 * (uncovered[i - 1] + uncovered[i]) * (v[i] - v[i - 1]).norm();
  return length;
}

}  // namespace hairrig
