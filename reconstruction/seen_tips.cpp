#include "reconstruction/seen_tips.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

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

// The oriented points within the window from `gap` to `gap + length` mm
// along `t` from `tip` (t unit, either sign), within `lateral` of its line,
// their direction within acos(min_cos) of it.
int64_t PointsAlong(const PointGrid& grid, const std::vector<OrientedPoint>& points,
                    const Eigen::Vector3f& tip, const Eigen::Vector3f& t, const SeenTipOptions& o,
                    float min_cos) {
  const double gap = o.points_gap_mm, length = o.points_window_mm, lateral = o.points_lateral_mm;
  const Eigen::Vector3f centre = tip + static_cast<float>(gap + 0.5 * length) * t;
  int64_t count = 0;
  grid.ForEachWithin(centre, std::hypot(0.5 * length, lateral), [&](int64_t j, double) {
    const OrientedPoint& p = points[static_cast<size_t>(j)];
    const Eigen::Vector3f v = p.position_mm - tip;
    const float along = v.dot(t);
    if (along >= gap && along <= gap + length && (v - along * t).norm() <= lateral &&
        std::abs(p.direction.dot(t)) >= min_cos)
      ++count;
  });
  return count;
}

// Whether the points run on past the tip: some lie ahead of it, and they
// number at least points_ahead_max_share of those behind it. Holds a grid
// over its own copy of the positions: not copied or moved.
class PointsRunOn {
 public:
  PointsRunOn(const PointsRunOn&) = delete;
  PointsRunOn& operator=(const PointsRunOn&) = delete;
  PointsRunOn(const std::vector<OrientedPoint>* points, const SeenTipOptions& o) : o_(o) {
    if (points == nullptr || o.points_ahead_max_share <= 0) return;
    points_ = points;
    for (const OrientedPoint& p : *points) positions_.push_back(p.position_mm);
    grid_ = std::make_unique<PointGrid>(positions_, std::max(1.0, o.points_lateral_mm));
    min_cos_ = static_cast<float>(std::cos(o.points_angle_deg * M_PI / 180.0));
  }
  bool operator()(const Eigen::Vector3f& tip, const Eigen::Vector3f& t) const {
    if (!grid_) return false;
    const int64_t ahead = PointsAlong(*grid_, *points_, tip, t, o_, min_cos_);
    if (ahead == 0) return false;
    const int64_t behind = PointsAlong(*grid_, *points_, tip, -t, o_, min_cos_);
    return static_cast<double>(ahead) >= o_.points_ahead_max_share * static_cast<double>(behind);
  }

 private:
  const SeenTipOptions& o_;
  const std::vector<OrientedPoint>* points_ = nullptr;
  std::vector<Eigen::Vector3f> positions_;
  std::unique_ptr<PointGrid> grid_;
  float min_cos_ = 1;
};

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
  if (!(points_ahead_max_share >= 0 && points_ahead_max_share <= 1))
    return InvalidArgument("seen tips: points_ahead_max_share must lie in [0, 1]");
  if (!(points_gap_mm >= 0 && points_window_mm > 0 && points_gap_mm + points_window_mm <= 50))
    return InvalidArgument(
        "seen tips: need points_gap_mm >= 0, points_window_mm > 0 and their sum <= 50");
  if (!(points_lateral_mm > 0 && points_lateral_mm <= 10))
    return InvalidArgument("seen tips: points_lateral_mm must lie in (0, 10]");
  if (!(points_angle_deg > 0 && points_angle_deg <= 90))
    return InvalidArgument("seen tips: points_angle_deg must lie in (0, 90]");
  if (!(reach_mm > 0 && reach_mm <= 10))
    return InvalidArgument("seen tips: reach_mm must lie in (0, 10]");
  return Status::Ok();
}

SeenTips::SeenTips() = default;
SeenTips::~SeenTips() = default;
SeenTips::SeenTips(SeenTips&&) noexcept = default;
SeenTips& SeenTips::operator=(SeenTips&&) noexcept = default;

SeenTips SeenTips::Find(const std::vector<StrandSegment>& segments, const SeenTipOptions& o,
                        const std::vector<OrientedPoint>* points) {
  SeenTips found;
  if (!o.enabled) return found;
  const PointsRunOn points_run_on(points, o);
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
    if (continued || points_run_on(tip, t)) continue;
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
