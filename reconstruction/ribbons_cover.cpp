// Covering the strand segments with ribbons (Sec. 5.2): CoverWithRibbons
// of reconstruction/ribbons.h.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include "reconstruction/mls.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/polyline_overlap.h"
#include "reconstruction/ribbons.h"
#include "reconstruction/ribbons_internal.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

using detail::Curve;
using detail::Curves;
using detail::GridIndex;
using detail::IndexedRibbon;
using detail::RibbonVertexIndex;
using detail::SurfacePoint;

namespace {

// `points` resampled evenly by arc length, about step_mm apart, both ends
// kept (at least two vertices when there are two).
Curve Resample(const Curve& points, double step_mm) {
  std::vector<double> arc(points.size(), 0.0);
  for (size_t k = 1; k < points.size(); ++k)
    arc[k] = arc[k - 1] + (points[k] - points[k - 1]).norm();
  if (points.size() < 2) return points;
  const int steps = std::max(1, static_cast<int>(std::lround(arc.back() / step_mm)));
  Curve out;
  size_t k = 0;
  for (int s = 0; s <= steps; ++s) {
    const double at = arc.back() * s / steps;
    while (k + 2 < points.size() && arc[k + 1] < at) ++k;
    const double span = arc[k + 1] - arc[k];
    const float t =
        span > 0 ? static_cast<float>(std::clamp((at - arc[k]) / span, 0.0, 1.0)) : 0.0f;
    out.push_back(points[k] + t * (points[k + 1] - points[k]));
  }
  return out;
}

// Fills the entries not marked valid from their nearest valid neighbour
// along the curve (earlier first); false when none is valid.
bool FillFromNeighbours(std::vector<Eigen::Vector3f>* values, const std::vector<uint8_t>& valid) {
  const size_t n = values->size();
  const auto first = std::find(valid.begin(), valid.end(), 1);
  if (first == valid.end()) return false;
  size_t last_valid = static_cast<size_t>(first - valid.begin());
  for (size_t k = 0; k < n; ++k) {
    if (valid[k])
      last_valid = k;
    else
      (*values)[k] = (*values)[last_valid];
  }
  return true;
}

// Everything the covering shares between ribbons.
struct CoverContext {
  const RibbonOptions& options;
  const PointSetSurface& surface;
  const PolylineVertexTable& vertices;  // the segments' vertices, tangents and owners
  const PointGrid& vertex_grid;         // over vertices.positions
  std::vector<int> ribbon_of;           // per segment, its ribbon (-1: none yet)
  std::vector<uint32_t> seen_in_round;  // per segment, the last candidate round that listed it
  uint32_t round = 0;
};

// Grows one ribbon from its seed segment. Isocurves are numbered by j: the
// seed's resampled polyline is 0, the expansions to the + side 1, 2, ...,
// to the - side -1, -2, ...; curves_[k] is isocurve first_j_ + k.
class RibbonGrower {
 public:
  RibbonGrower(CoverContext* context, int ribbon_id, int seed)
      : c_(*context),
        o_(context->options),
        id_(ribbon_id),
        seed_(seed),
        search_mm_(o_.spacing_mm + std::max(o_.spacing_mm, o_.step_mm)),
        index_(search_mm_) {}

  Ribbon Grow() {
    const uint32_t begin = c_.vertices.first[static_cast<size_t>(seed_)];
    const uint32_t end = c_.vertices.first[static_cast<size_t>(seed_) + 1];
    const Curve seed_points(c_.vertices.positions.begin() + begin,
                            c_.vertices.positions.begin() + end);
    AddIsocurve(Resample(seed_points, o_.step_mm), +1);
    c_.ribbon_of[static_cast<size_t>(seed_)] = id_;
    CoverNear(curves_.front());
    for (int side : {+1, -1}) {
      int failures = 0;
      while (failures < o_.max_failed_expansions &&
             static_cast<int>(curves_.size()) < o_.max_width) {
        Curve next;
        if (!NextIsocurve(side, &next)) break;
        AddIsocurve(std::move(next), side);
        failures = CoverNear(side > 0 ? curves_.back() : curves_.front()) > 0 ? 0 : failures + 1;
      }
    }
    Trim();
    Ribbon ribbon;
    ribbon.isocurves = std::move(curves_);
    ribbon.segments = covered_;
    ribbon.segments.push_back(seed_);
    std::sort(ribbon.segments.begin(), ribbon.segments.end());
    return ribbon;
  }

 private:
  int last_j() const { return first_j_ + static_cast<int>(curves_.size()) - 1; }

  void AddIsocurve(Curve curve, int side) {
    if (curves_.empty()) {
      curves_.push_back(std::move(curve));
    } else if (side > 0) {
      curves_.push_back(std::move(curve));
    } else {
      curves_.insert(curves_.begin(), std::move(curve));
      --first_j_;
    }
    index_.AddIsocurve(side > 0 ? curves_.back() : curves_.front(), side > 0 ? last_j() : first_j_);
  }

  // The expansion offsets b (unit) for the next isocurve on `side`.
  bool Offsets(int side, std::vector<Eigen::Vector3f>* offsets) const {
    const Curve& outer = side > 0 ? curves_.back() : curves_.front();
    const size_t n = outer.size();
    offsets->assign(n, Eigen::Vector3f::Zero());
    std::vector<uint8_t> valid(n, 0);
    if (curves_.size() == 1) {
      // b = +-o_R x n with n the MLS normal, signed consistently along the curve.
      std::vector<Eigen::Vector3f> normals(n, Eigen::Vector3f::Zero());
      std::vector<uint8_t> has_normal(n, 0);
      Eigen::Vector3f previous = Eigen::Vector3f::Zero();
      for (size_t i = 0; i < n; ++i) {
        Eigen::Vector3f projected, normal;
        if (!c_.surface.Project(outer[i], &projected, &normal, o_.min_neighbours)) continue;
        if (normal.dot(previous) < 0) normal = -normal;
        normals[i] = previous = normal;
        has_normal[i] = 1;
      }
      if (!FillFromNeighbours(&normals, has_normal)) return false;
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f b = PolylineTangent(outer, i).cross(normals[i]);
        if (b.norm() > 1e-3f)
          (*offsets)[i] = static_cast<float>(side) * b.normalized(), valid[i] = 1;
      }
    } else {
      // b = o_R x n_R with n_R = o_R x (outer - inner), signed outward: the
      // outward step between the outer isocurves, orthogonal to o_R.
      const Curve& inner = side > 0 ? curves_[curves_.size() - 2] : curves_[1];
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f o = PolylineTangent(outer, i);
        const Eigen::Vector3f across = outer[i] - inner[i];
        const Eigen::Vector3f b = across - across.dot(o) * o;
        if (b.norm() > 1e-4f) (*offsets)[i] = b.normalized(), valid[i] = 1;
      }
    }
    return FillFromNeighbours(offsets, valid);
  }

  // R' = R + b Delta, MLS-projected vertex by vertex, smoothed by Eq. 3.
  bool NextIsocurve(int side, Curve* next) const {
    std::vector<Eigen::Vector3f> offsets;
    if (!Offsets(side, &offsets)) return false;
    const Curve& outer = side > 0 ? curves_.back() : curves_.front();
    next->resize(outer.size());
    for (size_t i = 0; i < outer.size(); ++i) {
      const Eigen::Vector3f moved = outer[i] + offsets[i] * static_cast<float>(o_.spacing_mm);
      Eigen::Vector3f projected, normal;
      (*next)[i] =
          c_.surface.Project(moved, &projected, &normal, o_.min_neighbours) ? projected : moved;
    }
    *next = SmoothPolyline(*next, o_.smooth_position, o_.smooth_orientation, o_.smooth_curvature);
    return true;
  }

  // Rules 1-2 and T_bad: whether isocurves j_lo..j_hi cover the segment.
  bool Covers(int segment, int j_lo, int j_hi) const {
    const PolylineVertexTable& v = c_.vertices;
    const uint32_t begin = v.first[static_cast<size_t>(segment)],
                   end = v.first[static_cast<size_t>(segment) + 1];
    const double allowed =
        std::min(static_cast<double>(o_.max_bad_points), o_.max_bad_fraction * (end - begin));
    const double near2 = o_.spacing_mm * o_.spacing_mm;
    const IndexedRibbon ribbon{curves_, first_j_, index_};
    // From both ends inwards, alternately, each end walking the grid from
    // its previous vertex: a segment that leaves the ribbon mostly does so
    // at an end, and is turned down after a few vertices.
    std::optional<GridIndex> hints[2];
    int bad = 0;
    for (uint32_t front = begin, back = end, n = 0; front < back; ++n) {
      const int side = static_cast<int>(n % 2);
      const uint32_t k = side == 0 ? front++ : --back;
      SurfacePoint q;
      const bool good = ribbon.Project(v.positions[k], j_lo, j_hi, search_mm_, &q, &hints[side]) &&
                        q.distance2 <= near2 &&
                        std::abs(v.tangents[k].dot(q.orientation)) >= o_.min_turn_cos;
      if (!good && ++bad >= allowed) return false;
    }
    return bad < allowed;
  }

  // Covers the uncovered segments that come near `curve` if the whole ribbon
  // covers them; returns how many.
  int CoverNear(const Curve& curve) {
    const uint32_t round = ++c_.round;
    const double reach = o_.spacing_mm + std::max(o_.spacing_mm, o_.step_mm);
    std::vector<int> candidates;
    for (const Eigen::Vector3f& p : curve) {
      c_.vertex_grid.ForEachWithin(p, reach, [&](uint32_t u, double) {
        const uint32_t s = c_.vertices.owner[u];
        if (c_.ribbon_of[s] >= 0 || c_.seen_in_round[s] == round) return;
        c_.seen_in_round[s] = round;
        candidates.push_back(static_cast<int>(s));
      });
    }
    std::sort(candidates.begin(), candidates.end());
    int covered = 0;
    for (int s : candidates) {
      if (!Covers(s, first_j_, last_j())) continue;
      c_.ribbon_of[static_cast<size_t>(s)] = id_;
      covered_.push_back(s);
      ++covered;
    }
    return covered;
  }

  // Removes outer isocurves (never the seed's) while every covered segment
  // stays covered.
  void Trim() {
    for (bool trimmed = true; trimmed;) {
      trimmed = false;
      if (last_j() > 0 && CoversAll(first_j_, last_j() - 1)) {
        curves_.pop_back();
        trimmed = true;
      }
      if (first_j_ < 0 && CoversAll(first_j_ + 1, last_j())) {
        curves_.erase(curves_.begin());
        ++first_j_;
        trimmed = true;
      }
    }
  }

  bool CoversAll(int j_lo, int j_hi) const {
    return std::all_of(covered_.begin(), covered_.end(),
                       [&](int s) { return Covers(s, j_lo, j_hi); });
  }

  CoverContext& c_;
  const RibbonOptions& o_;
  int id_, seed_;
  // A vertex within Delta of the ribbon has a grid vertex within this (a
  // cell's half diagonal, with room for uneven cells).
  double search_mm_;
  Curves curves_;
  int first_j_ = 0;
  RibbonVertexIndex index_;   // keeps trimmed isocurves' vertices: every search names its isocurves
  std::vector<int> covered_;  // besides the seed
};

double CurveLength(const Curve& curve) {
  double length = 0;
  for (size_t k = 1; k < curve.size(); ++k) length += (curve[k] - curve[k - 1]).norm();
  return length;
}

RibbonSummary Summarise(const std::vector<Ribbon>& ribbons) {
  RibbonSummary s;
  s.ribbons = static_cast<int64_t>(ribbons.size());
  for (const Ribbon& r : ribbons) {
    (r.segments.size() > 1 ? s.covered_segments : s.uncovered_segments) +=
        static_cast<int64_t>(r.segments.size());
    s.mean_width += r.width();
    s.mean_length_mm += CurveLength(r.center());
  }
  if (!ribbons.empty()) {
    s.mean_width /= static_cast<double>(ribbons.size());
    s.mean_length_mm /= static_cast<double>(ribbons.size());
  }
  return s;
}

}  // namespace

Status RibbonOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(spacing_mm)) return InvalidArgument("ribbon spacing_mm must be positive");
  if (!positive(step_mm)) return InvalidArgument("ribbon step_mm must be positive");
  if (!(min_turn_cos >= 0 && min_turn_cos <= 1))
    return InvalidArgument("ribbon min_turn_cos must lie in 0..1");
  if (max_bad_points < 1) return InvalidArgument("ribbon max_bad_points must be at least 1");
  if (!(max_bad_fraction > 0 && max_bad_fraction <= 1))
    return InvalidArgument("ribbon max_bad_fraction must lie in (0, 1]");
  if (max_failed_expansions < 1)
    return InvalidArgument("ribbon max_failed_expansions must be at least 1");
  if (!positive(sigma_mm)) return InvalidArgument("ribbon sigma_mm must be positive");
  if (min_neighbours < 1) return InvalidArgument("ribbon min_neighbours must be at least 1");
  if (!(smooth_position > 0) || !(smooth_orientation >= 0) || !(smooth_curvature >= 0)) {
    return InvalidArgument(
        "ribbon smoothing weights: position must be positive, the others non-negative");
  }
  if (max_width < 1) return InvalidArgument("ribbon max_width must be at least 1");
  return Status::Ok();
}

std::vector<Ribbon> CoverWithRibbons(const std::vector<OrientedPoint>& points,
                                     const std::vector<StrandSegment>& segments,
                                     const RibbonOptions& options, RibbonSummary* summary) {
  std::vector<Eigen::Vector3f> positions(points.size());
  for (size_t k = 0; k < points.size(); ++k) positions[k] = points[k].position_mm;
  const PointSetSurface surface(positions, options.sigma_mm);
  std::vector<const Curve*> polylines;
  for (const StrandSegment& s : segments) polylines.push_back(&s.points_mm);
  const PolylineVertexTable vertices = TabulatePolylines(polylines);
  const PointGrid vertex_grid(vertices.positions,
                              options.spacing_mm + std::max(options.spacing_mm, options.step_mm));
  CoverContext context{options,
                       surface,
                       vertices,
                       vertex_grid,
                       std::vector<int>(segments.size(), -1),
                       std::vector<uint32_t>(segments.size(), 0),
                       0};

  // Sec. 5.2: the longest uncovered segment first.
  std::vector<double> length(segments.size());
  for (size_t s = 0; s < segments.size(); ++s) length[s] = segments[s].Length();
  std::vector<int> order(segments.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return length[a] > length[b]; });
  std::vector<Ribbon> ribbons;
  for (int seed : order) {
    if (context.ribbon_of[static_cast<size_t>(seed)] >= 0 ||
        segments[static_cast<size_t>(seed)].points_mm.empty())
      continue;
    RibbonGrower grower(&context, static_cast<int>(ribbons.size()), seed);
    ribbons.push_back(grower.Grow());
  }
  if (summary != nullptr) *summary = Summarise(ribbons);
  return ribbons;
}

}  // namespace hairrig
