#include "reconstruction/seen_tips.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "reconstruction/point_grid.h"
#include "reconstruction/segment_coverage.h"

namespace hairrig {

namespace {

// The segment's direction at its tip end: the chord over its last three
// steps (one step's chord turns with the segment's jitter).
Eigen::Vector3f TipTangent(const std::vector<Eigen::Vector3f>& points) {
  const size_t back = std::min<size_t>(3, points.size() - 1);
  const Eigen::Vector3f d = points.back() - points[points.size() - 1 - back];
  const float n = d.norm();
  return n > 0 ? Eigen::Vector3f(d / n) : Eigen::Vector3f::Zero();
}

// Every segment vertex with its segment's index and its tangent.
struct SegmentVertices {
  std::vector<Eigen::Vector3f> positions, tangents;
  std::vector<uint32_t> segment;
};

SegmentVertices AllVertices(const std::vector<StrandSegment>& segments) {
  SegmentVertices v;
  for (size_t s = 0; s < segments.size(); ++s) {
    const std::vector<Eigen::Vector3f>& points = segments[s].points_mm;
    for (size_t k = 0; k < points.size(); ++k) {
      v.positions.push_back(points[k]);
      v.tangents.push_back(PolylineTangent(points.data(), points.size(), k));
      v.segment.push_back(static_cast<uint32_t>(s));
    }
  }
  return v;
}

// How far ahead of `tip` along `t` the segment's furthest vertex lies.
float Reach(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& tip,
            const Eigen::Vector3f& t) {
  float furthest = -std::numeric_limits<float>::infinity();
  for (const Eigen::Vector3f& p : points) furthest = std::max(furthest, (p - tip).dot(t));
  return furthest;
}

}  // namespace

struct SeenTips::Index {
  std::vector<Eigen::Vector3f> tips, tangents;
  std::unique_ptr<PointGrid> grid;  // over `tips`, which stay put
  double reach_mm = 0;
};

Status SeenTipOptions::Check() const {
  if (!(ahead_min_mm >= 0 && ahead_max_mm > ahead_min_mm && ahead_max_mm <= 50))
    return InvalidArgument("seen tips: need 0 <= ahead_min_mm < ahead_max_mm <= 50");
  if (!(lateral_mm > 0 && lateral_mm <= 10))
    return InvalidArgument("seen tips: lateral_mm must lie in (0, 10]");
  if (!(max_angle_deg > 0 && max_angle_deg <= 90))
    return InvalidArgument("seen tips: max_angle_deg must lie in (0, 90]");
  if (!(min_seen_length_mm >= 0))
    return InvalidArgument("seen tips: min_seen_length_mm must be non-negative");
  if (!(min_strand_mm >= 0))
    return InvalidArgument("seen tips: min_strand_mm must be non-negative");
  if (!(carry_on_mm >= 0 && carry_on_mm <= 100))
    return InvalidArgument("seen tips: carry_on_mm must lie in [0, 100]");
  if (!(reach_mm > 0 && reach_mm <= 10))
    return InvalidArgument("seen tips: reach_mm must lie in (0, 10]");
  return Status::Ok();
}

SeenTips::SeenTips() = default;
SeenTips::~SeenTips() = default;
SeenTips::SeenTips(SeenTips&&) noexcept = default;
SeenTips& SeenTips::operator=(SeenTips&&) noexcept = default;

SeenTips SeenTips::Find(const std::vector<StrandSegment>& segments, const SeenTipOptions& o) {
  SeenTips found;
  if (!o.enabled) return found;
  const SegmentVertices vertices = AllVertices(segments);
  const PointGrid grid(vertices.positions, 2.0);
  const float min_cos = static_cast<float>(std::cos(o.max_angle_deg * M_PI / 180.0));
  const double mid = 0.5 * (o.ahead_min_mm + o.ahead_max_mm);
  // Every vertex the test can accept lies within this of the window's middle.
  const double search = std::hypot(0.5 * (o.ahead_max_mm - o.ahead_min_mm), o.lateral_mm);
  auto index = std::make_shared<Index>();
  index->reach_mm = o.reach_mm;
  for (size_t s = 0; s < segments.size(); ++s) {
    const std::vector<Eigen::Vector3f>& points = segments[s].points_mm;
    if (points.size() < 2) continue;
    ++found.examined_;
    if (segments[s].Length() < o.min_seen_length_mm) continue;
    const Eigen::Vector3f tip = points.back(), t = TipTangent(points);
    if (t.isZero()) continue;
    const Eigen::Vector3f centre = tip + static_cast<float>(mid) * t;
    // A segment whose reach fell short cannot continue the tip through any of
    // its vertices: its reach is not computed again for the next one.
    size_t short_segment = s;
    const bool continued = grid.AnyWithin(centre, search, [&](int64_t j, double) {
      const size_t other = vertices.segment[static_cast<size_t>(j)];
      if (other == s || other == short_segment) return false;
      const Eigen::Vector3f v = vertices.positions[static_cast<size_t>(j)] - tip;
      const float ahead = v.dot(t);
      if (!(ahead >= o.ahead_min_mm && ahead <= o.ahead_max_mm &&
            (v - ahead * t).norm() <= o.lateral_mm &&
            std::abs(vertices.tangents[static_cast<size_t>(j)].dot(t)) >= min_cos))
        return false;
      if (o.carry_on_mm <= 0 || Reach(segments[other].points_mm, tip, t) >= o.carry_on_mm)
        return true;
      short_segment = other;
      return false;
    });
    if (continued) continue;
    index->tips.push_back(tip);
    index->tangents.push_back(t);
  }
  if (index->tips.empty()) return found;
  index->grid = std::make_unique<PointGrid>(index->tips, std::max(1.0, o.reach_mm));
  found.index_ = std::move(index);
  return found;
}

bool SeenTips::Reached(const Eigen::Vector3f& p, const Eigen::Vector3f& direction) const {
  if (!index_) return false;
  return index_->grid->AnyWithin(p, index_->reach_mm, [&](int64_t j, double) {
    return index_->tangents[static_cast<size_t>(j)].dot(direction) > 0.5f;
  });
}

size_t SeenTips::size() const { return index_ ? index_->tips.size() : 0; }

}  // namespace hairrig
