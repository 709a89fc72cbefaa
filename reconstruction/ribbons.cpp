#include "reconstruction/ribbons.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "core/parallel.h"
#include "reconstruction/binary_mrf.h"
#include "reconstruction/circle_fit.h"
#include "reconstruction/mls.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/polyline_overlap.h"
#include "reconstruction/scalp_distance.h"

namespace hairrig {

namespace {

using Curve = std::vector<Eigen::Vector3f>;
using Curves = std::vector<Curve>;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------
// Projection onto the tessellated grid (R^{-1} of Sec. 5.2).

// The best candidate so far; w counts isocurves from curves[0].
struct SurfacePoint {
  double distance2 = kInfinity;
  float w = 0, l = 0;
  Eigen::Vector3f closest = Eigen::Vector3f::Zero(), orientation = Eigen::Vector3f::Zero();
};

// Barycentric weights of the point of triangle (a, b, c) nearest p; the
// triangle may be degenerate (a segment, a point).
Eigen::Vector3f ClosestBarycentric(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                   const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const Eigen::Vector3f n = ab.cross(ac);
  const float n2 = n.squaredNorm();
  if (n2 > 1e-12f * ab.squaredNorm() * ac.squaredNorm() && n2 > 0) {
    const float beta = ap.cross(ac).dot(n) / n2, gamma = ab.cross(ap).dot(n) / n2;
    if (beta >= 0 && gamma >= 0 && beta + gamma <= 1) return {1 - beta - gamma, beta, gamma};
  }
  // Outside (or degenerate): the nearest point of the three edges.
  const Eigen::Vector3f* corner[3] = {&a, &b, &c};
  Eigen::Vector3f best_weights(1, 0, 0);
  float best2 = std::numeric_limits<float>::max();
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3f& from = *corner[e];
    const Eigen::Vector3f edge = *corner[(e + 1) % 3] - from;
    const float len2 = edge.squaredNorm();
    const float t = len2 > 0 ? std::clamp((p - from).dot(edge) / len2, 0.0f, 1.0f) : 0.0f;
    const float d2 = (from + t * edge - p).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best_weights.setZero();
      best_weights(e) = 1 - t;
      best_weights((e + 1) % 3) += t;
    }
  }
  return best_weights;
}

struct GridIndex {
  int j, i;
};

// Tries the triangle of grid vertices `corner` (indices into `curves`).
void ProjectOnTriangle(const Curves& curves, const GridIndex (&corner)[3], const Eigen::Vector3f& p,
                       SurfacePoint* best) {
  const auto at = [&](const GridIndex& g) -> const Eigen::Vector3f& {
    return curves[static_cast<size_t>(g.j)][static_cast<size_t>(g.i)];
  };
  const Eigen::Vector3f weights =
      ClosestBarycentric(p, at(corner[0]), at(corner[1]), at(corner[2]));
  Eigen::Vector3f closest = Eigen::Vector3f::Zero();
  for (int k = 0; k < 3; ++k) closest += weights(k) * at(corner[k]);
  const double d2 = (closest - p).squaredNorm();
  if (d2 >= best->distance2) return;
  best->distance2 = d2;
  best->closest = closest;
  best->w = best->l = 0;
  Eigen::Vector3f orientation = Eigen::Vector3f::Zero();
  for (int k = 0; k < 3; ++k) {
    best->w += weights(k) * static_cast<float>(corner[k].j);
    best->l += weights(k) * static_cast<float>(corner[k].i);
    orientation += weights(k) * PolylineTangent(curves[static_cast<size_t>(corner[k].j)],
                                                static_cast<size_t>(corner[k].i));
  }
  best->orientation =
      orientation.norm() > 0 ? Eigen::Vector3f(orientation.normalized()) : orientation;
}

// Which part of the grid a projection looks at: isocurves lo..hi (inclusive,
// indices into the curves) take part; cells are named by their first corner.
struct CellRange {
  int lo = 0, hi = 0;
  int j_begin = 0, j_end = 0, i_begin = 0, i_end = 0;
};

// Every cell of the range as two triangles; a cell on the last isocurve of
// the rows (a 1-isocurve ribbon) or past the last vertex degenerates to a
// segment.
// With `skip_far_cells`, a cell whose bounding ball about its corners'
// centroid lies no nearer than the best point so far is skipped: its
// triangles cannot do better, so the result is the same.
void ProjectOnCells(const Curves& curves, const CellRange& range, const Eigen::Vector3f& p,
                    SurfacePoint* best, bool skip_far_cells = false) {
  const int last_i = static_cast<int>(curves[static_cast<size_t>(range.lo)].size()) - 1;
  const auto at = [&](int j, int i) -> const Eigen::Vector3f& {
    return curves[static_cast<size_t>(j)][static_cast<size_t>(i)];
  };
  for (int j = range.j_begin; j < range.j_end; ++j) {
    const int j2 = std::min(j + 1, range.hi);
    for (int i = range.i_begin; i < range.i_end; ++i) {
      const int i2 = std::min(i + 1, last_i);
      if (skip_far_cells) {
        const Eigen::Vector3f centre = 0.25f * (at(j, i) + at(j, i2) + at(j2, i2) + at(j2, i));
        const float radius = std::sqrt(
            std::max({(at(j, i) - centre).squaredNorm(), (at(j, i2) - centre).squaredNorm(),
                      (at(j2, i2) - centre).squaredNorm(), (at(j2, i) - centre).squaredNorm()}));
        const float gap = (p - centre).norm() - radius;
        if (gap > 0 && static_cast<double>(gap) * gap >= best->distance2) continue;
      }
      ProjectOnTriangle(curves, {{j, i}, {j, i2}, {j2, i2}}, p, best);
      if (j2 != j && i2 != i) ProjectOnTriangle(curves, {{j, i}, {j2, i2}, {j2, i}}, p, best);
    }
  }
}

// Every cell of isocurves lo..hi.
CellRange AllCells(const Curves& curves, int lo, int hi) {
  const int length = static_cast<int>(curves[static_cast<size_t>(lo)].size()) - 1;
  return {lo, hi, lo, std::max(lo + 1, hi), 0, std::max(1, length)};
}

// The (up to four) cells that share vertex (j, i), within isocurves lo..hi.
CellRange CellsAround(const Curves& curves, int lo, int hi, int j, int i) {
  const int length = static_cast<int>(curves[static_cast<size_t>(lo)].size()) - 1;
  return {lo,
          hi,
          std::max(lo, j - 1),
          hi > lo ? std::min(j + 1, hi) : lo + 1,
          std::max(0, i - 1),
          length > 0 ? std::min(i + 1, length) : 1};
}

RibbonCoordinates ToCoordinates(const SurfacePoint& s, const Eigen::Vector3f& p, int w_offset) {
  RibbonCoordinates c;
  c.w = s.w - static_cast<float>(w_offset);
  c.l = s.l;
  c.closest = s.closest;
  c.distance_mm = static_cast<float>(std::sqrt(s.distance2));
  c.orientation = s.orientation;
  if (!std::isfinite(s.distance2)) c.closest = p;
  return c;
}

// A hash grid over a ribbon's vertices, each named by (isocurve, vertex);
// isocurves are numbered by a caller's index that stays valid as isocurves
// are added on either side.
class RibbonVertexIndex {
 public:
  explicit RibbonVertexIndex(double cell_mm) : cell_mm_(cell_mm) {}

  void AddIsocurve(const Curve& curve, int j) {
    for (size_t i = 0; i < curve.size(); ++i)
      cells_[Key(Cell(curve[i]))].push_back({curve[i], j, static_cast<int>(i)});
  }

  // The vertex nearest q within `radius_mm` on isocurves j_lo..j_hi; false when none.
  bool Nearest(const Eigen::Vector3f& q, double radius_mm, int j_lo, int j_hi,
               GridIndex* nearest) const {
    const Eigen::Vector3i centre = Cell(q);
    const int reach = static_cast<int>(std::ceil(radius_mm / cell_mm_));
    float best2 = static_cast<float>(radius_mm * radius_mm);
    bool found = false;
    for (int dz = -reach; dz <= reach; ++dz)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
          const auto cell = cells_.find(Key(centre + Eigen::Vector3i(dx, dy, dz)));
          if (cell == cells_.end()) continue;
          for (const Entry& e : cell->second) {
            if (e.j < j_lo || e.j > j_hi) continue;
            const float d2 = (e.position - q).squaredNorm();
            if (d2 <= best2) best2 = d2, *nearest = {e.j, e.i}, found = true;
          }
        }
    return found;
  }

 private:
  struct Entry {
    Eigen::Vector3f position;
    int j, i;
  };
  Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
    return (p.cast<double>() / cell_mm_).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    const auto wrap = [](int v) { return static_cast<int64_t>(v) & 0x1fffff; };  // 21 bits per axis
    return (wrap(c.x()) << 42) | (wrap(c.y()) << 21) | wrap(c.z());
  }

  double cell_mm_;
  std::unordered_map<int64_t, std::vector<Entry>> cells_;
};

// A ribbon's isocurves with the index: curves[k] is isocurve first_j + k.
struct IndexedRibbon {
  const Curves& curves;
  int first_j;
  const RibbonVertexIndex& index;

  // Projection onto isocurves j_lo..j_hi (index numbers) searched around the
  // nearest vertex within radius_mm; false when there is none. `hint`
  // (optional) carries the nearest vertex from one call to the next: along a
  // polyline, walking downhill from the previous vertex's is much cheaper
  // than the index.
  bool Project(const Eigen::Vector3f& p, int j_lo, int j_hi, double radius_mm, SurfacePoint* out,
               std::optional<GridIndex>* hint = nullptr) const {
    GridIndex nearest{0, 0};
    const bool walked = hint != nullptr && hint->has_value() &&
                        WalkDownhill(p, j_lo, j_hi, **hint, &nearest) <= radius_mm * radius_mm;
    if (!walked && !index.Nearest(p, radius_mm, j_lo, j_hi, &nearest)) return false;
    if (hint != nullptr) *hint = nearest;
    *out = SurfacePoint{};
    ProjectOnCells(
        curves, CellsAround(curves, j_lo - first_j, j_hi - first_j, nearest.j - first_j, nearest.i),
        p, out);
    return true;
  }

 private:
  const Eigen::Vector3f& At(const GridIndex& g) const {
    return curves[static_cast<size_t>(g.j - first_j)][static_cast<size_t>(g.i)];
  }

  // From `start` to the neighbouring vertex nearest p while one is nearer;
  // the squared distance of where it stops.
  float WalkDownhill(const Eigen::Vector3f& p, int j_lo, int j_hi, GridIndex start,
                     GridIndex* end) const {
    const int last_i = static_cast<int>(curves[0].size()) - 1;
    start.j = std::clamp(start.j, j_lo, j_hi);
    start.i = std::clamp(start.i, 0, last_i);
    float best2 = (At(start) - p).squaredNorm();
    for (bool moved = true; moved;) {
      moved = false;
      const GridIndex from = start;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const GridIndex g{from.j + dj, from.i + di};
          if (g.j < j_lo || g.j > j_hi || g.i < 0 || g.i > last_i) continue;
          const float d2 = (At(g) - p).squaredNorm();
          if (d2 < best2) best2 = d2, start = g, moved = true;
        }
      }
    }
    *end = start;
    return best2;
  }
};

// ---------------------------------------------------------------------------
// Covering (Sec. 5.2).

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

// ---------------------------------------------------------------------------
// Connection analysis (Sec. 6.1).

// Projections onto finished ribbons, each indexed when first asked for.
class RibbonProjector {
 public:
  explicit RibbonProjector(const std::vector<Ribbon>& ribbons)
      : ribbons_(ribbons), indices_(ribbons.size()) {}

  RibbonCoordinates Project(int r, const Eigen::Vector3f& p) {
    SurfacePoint q;
    if (!ProjectNear(r, p, &q)) return ProjectOntoRibbon(ribbons_[static_cast<size_t>(r)], p);
    return ToCoordinates(q, p, 0);
  }

  // Whether the segment's vertex order agrees with the ribbon's l direction
  // at the majority of its vertices near the ribbon (at its middle vertex
  // when none is).
  bool AlongRibbon(int r, const Curve& segment) {
    int votes = 0, voters = 0;
    for (size_t k = 0; k < segment.size(); ++k) {
      SurfacePoint q;
      if (!ProjectNear(r, segment[k], &q)) continue;
      votes += PolylineTangent(segment, k).dot(q.orientation) >= 0 ? 1 : -1;
      ++voters;
    }
    if (voters == 0) {
      const size_t middle = segment.size() / 2;
      return PolylineTangent(segment, middle).dot(Project(r, segment[middle]).orientation) >= 0;
    }
    return votes >= 0;
  }

 private:
  static constexpr double kSearchMm = 6.0;  // "near": a ribbon vertex this close

  bool ProjectNear(int r, const Eigen::Vector3f& p, SurfacePoint* q) {
    const Ribbon& ribbon = ribbons_[static_cast<size_t>(r)];
    auto& index = indices_[static_cast<size_t>(r)];
    if (index == nullptr) {
      index = std::make_unique<RibbonVertexIndex>(kSearchMm);
      for (int j = 0; j <= ribbon.width(); ++j)
        index->AddIsocurve(ribbon.isocurves[static_cast<size_t>(j)], j);
    }
    return IndexedRibbon{ribbon.isocurves, 0, *index}.Project(p, 0, ribbon.width(), kSearchMm, q);
  }

  const std::vector<Ribbon>& ribbons_;
  std::vector<std::unique_ptr<RibbonVertexIndex>> indices_;
};

// One end of a segment in a ribbon, with the circle fitted to its piece P.
struct SegmentEnd {
  int segment = -1, ribbon = -1;
  bool at_first = false;
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f outward = Eigen::Vector3f::Zero();  // leaving the segment at this end (unit)
  std::vector<Eigen::Vector3d> piece;  // the K vertices nearest the end, the end last
  Circle3 circle;                      // normal: counter-clockwise along `piece`
  bool fitted = false;
};

SegmentEnd MakeEnd(const Curve& points, int segment, int ribbon, bool at_first, int k_vertices) {
  SegmentEnd end;
  end.segment = segment;
  end.ribbon = ribbon;
  end.at_first = at_first;
  const size_t n = points.size();
  const size_t k = std::min(n, static_cast<size_t>(k_vertices));
  for (size_t m = 0; m < k; ++m) {
    const size_t from_end = k - 1 - m;  // the piece runs towards the end
    end.piece.push_back(points[at_first ? from_end : n - 1 - from_end].cast<double>());
  }
  end.position = points[at_first ? 0 : n - 1];
  const Eigen::Vector3f inner =
      points[at_first ? std::min<size_t>(2, n - 1) : n - 1 - std::min<size_t>(2, n - 1)];
  const Eigen::Vector3f out = end.position - inner;
  end.outward = out.norm() > 0 ? Eigen::Vector3f(out.normalized()) : out;
  end.fitted = std::isfinite(FitCircle3(end.piece, &end.circle));
  if (end.fitted) OrientByTraversal(end.piece, &end.circle);
  return end;
}

enum class Verdict { kLink, kDirection, kRms, kCurvature, kTorsion, kOverlap };
constexpr int kVerdicts = 6;

class ArcJudge {
 public:
  explicit ArcJudge(const ConnectionOptions& o)
      : o_(o),
        min_curvature_(1.0 / o.straight_radius_mm),
        min_normal_cos_(std::cos(o.max_normal_angle_deg * M_PI / 180.0)) {}

  // The tests of Sec. 6.1 on the arc from end a's segment to end b's, in the
  // order ConnectionSummary counts them.
  Verdict Judge(const SegmentEnd& a, const SegmentEnd& b, Circle3* joint, double* rms) const {
    if (!GapContinuesBoth(a, b)) return Verdict::kDirection;
    const double kappa_a = Curvature(a.circle), kappa_b = Curvature(b.circle);
    if (std::abs(kappa_a - kappa_b) / (kappa_a + kappa_b) > o_.max_curvature_ratio)
      return Verdict::kCurvature;
    // The arc runs along a's piece to its end, then along b's piece from its end: b's normal flips.
    const Circle3 piece_a = a.circle;
    Circle3 piece_b = b.circle;
    piece_b.normal = -piece_b.normal;
    if (!NormalsAgree(piece_a, piece_b)) return Verdict::kTorsion;
    std::vector<Eigen::Vector3d> arc = a.piece;
    arc.insert(arc.end(), b.piece.rbegin(), b.piece.rend());
    *rms = FitCircle3(arc, joint);
    if (!(*rms <= o_.max_rms_mm)) return Verdict::kRms;
    OrientByTraversal(arc, joint);
    if (SweepOverlap(arc, *joint) > o_.max_overlap) return Verdict::kOverlap;
    if (std::abs(2 * Curvature(*joint) - kappa_a - kappa_b) / (kappa_a + kappa_b) >
        o_.max_curvature_ratio) {
      return Verdict::kCurvature;
    }
    if (!NormalsAgree(*joint, piece_a) || !NormalsAgree(*joint, piece_b)) return Verdict::kTorsion;
    return Verdict::kLink;
  }

 private:
  double Curvature(const Circle3& c) const { return std::max(c.Curvature(), min_curvature_); }
  bool Straight(const Circle3& c) const { return c.radius > o_.straight_radius_mm; }
  bool NormalsAgree(const Circle3& x, const Circle3& y) const {
    return Straight(x) || Straight(y) || x.normal.dot(y.normal) >= min_normal_cos_;
  }
  bool GapContinuesBoth(const SegmentEnd& a, const SegmentEnd& b) const {
    constexpr float kCoincidentMm = 0.5f;
    const Eigen::Vector3f gap = b.position - a.position;
    if (gap.norm() < kCoincidentMm) return true;
    const Eigen::Vector3f towards_b = gap.normalized();
    return a.outward.dot(towards_b) > o_.min_gap_cos && b.outward.dot(-towards_b) > o_.min_gap_cos;
  }

  const ConnectionOptions& o_;
  double min_curvature_, min_normal_cos_;
};

// The verdicts on the pairs of one end with the ends after it.
struct EndVerdicts {
  struct Accepted {
    uint32_t partner;
    double rms_mm, radius_mm;
  };
  std::vector<Accepted> accepted;
  int64_t counts[kVerdicts] = {};  // per Verdict
};

void AddCounts(const EndVerdicts& v, ConnectionSummary* s) {
  const auto count = [&](Verdict which) { return v.counts[static_cast<int>(which)]; };
  for (int64_t c : v.counts) s->pairs_tried += c;
  s->links += count(Verdict::kLink);
  s->rejected_direction += count(Verdict::kDirection);
  s->rejected_rms += count(Verdict::kRms);
  s->rejected_curvature += count(Verdict::kCurvature);
  s->rejected_torsion += count(Verdict::kTorsion);
  s->rejected_overlap += count(Verdict::kOverlap);
}

// Every segment end in a ribbon, with its piece's circle (ends of segments
// with fewer than 3 vertices left out).
std::vector<SegmentEnd> FitEnds(const std::vector<StrandSegment>& segments,
                                const std::vector<int>& ribbon_of, const ConnectionOptions& o) {
  std::vector<std::pair<int, bool>> which;
  for (size_t seg = 0; seg < segments.size(); ++seg) {
    if (ribbon_of[seg] < 0 || segments[seg].points_mm.size() < 3) continue;
    which.emplace_back(static_cast<int>(seg), true);
    which.emplace_back(static_cast<int>(seg), false);
  }
  std::vector<SegmentEnd> ends(which.size());
  ParallelFor(which.size(), o.threads, [&] {
    return [&](size_t k) {
      const auto [seg, at_first] = which[k];
      ends[k] = MakeEnd(segments[static_cast<size_t>(seg)].points_mm, seg,
                        ribbon_of[static_cast<size_t>(seg)], at_first, o.fit_vertices);
    };
  });
  ends.erase(
      std::remove_if(ends.begin(), ends.end(), [](const SegmentEnd& e) { return !e.fitted; }),
      ends.end());
  return ends;
}

// The verdicts on every pair of ends in different ribbons within reach.
std::vector<EndVerdicts> JudgePairs(const std::vector<SegmentEnd>& ends,
                                    const ConnectionOptions& o) {
  std::vector<Eigen::Vector3f> positions;
  for (const SegmentEnd& e : ends) positions.push_back(e.position);
  const PointGrid grid(positions, o.max_end_gap_mm);
  const ArcJudge judge(o);
  std::vector<EndVerdicts> verdicts(ends.size());
  ParallelFor(ends.size(), o.threads, [&] {
    return [&](size_t e) {
      std::vector<uint32_t> partners;
      grid.ForEachWithin(positions[e], o.max_end_gap_mm, [&](uint32_t f, double) {
        if (f > e && ends[f].ribbon != ends[e].ribbon) partners.push_back(f);
      });
      std::sort(partners.begin(), partners.end());
      for (uint32_t f : partners) {
        Circle3 joint;
        double rms = 0;
        const Verdict verdict = judge.Judge(ends[e], ends[f], &joint, &rms);
        ++verdicts[e].counts[static_cast<int>(verdict)];
        if (verdict == Verdict::kLink) verdicts[e].accepted.push_back({f, rms, joint.radius});
      }
    };
  });
  return verdicts;
}

// ---------------------------------------------------------------------------
// Direction analysis (Sec. 6.2).

// Whether the link's piece on side k (from the fitted end inwards) runs
// towards increasing l.
bool PieceRunsWithL(const RibbonLink& link, int k) {
  return link.at_first_vertex[k] == link.segment_along_ribbon[k];
}

// A link is compatible with equal directions (both kept or both reversed)
// when exactly one piece runs with its ribbon's l; otherwise with different ones.
bool NeedsEqualDirections(const RibbonLink& link) {
  return PieceRunsWithL(link, 0) != PieceRunsWithL(link, 1);
}

// Eq. 5 for D(R) = 0 -> L (the cost of 0 -> L; L -> 0 costs its negative).
double RibbonEnergy(const Ribbon& r, const ScalpDistance& zeta, const RibbonDirectionOptions& o) {
  if (r.isocurves.empty() || r.center().empty()) return 0;
  const Eigen::Vector3f& first = r.center().front();
  const Eigen::Vector3f& last = r.center().back();
  double e = first.dot(o.down) - last.dot(o.down);
  if (zeta.available()) e += zeta(first) - zeta(last);
  return e / (2 * o.height_scale_mm);
}

// Psi: the smaller of the numbers of distinct segments on the two sides.
int LinkStrength(std::vector<int> side_a, std::vector<int> side_b) {
  const auto distinct = [](std::vector<int>* v) {
    std::sort(v->begin(), v->end());
    return static_cast<int>(std::unique(v->begin(), v->end()) - v->begin());
  };
  return std::min(distinct(&side_a), distinct(&side_b));
}

bool ValidLink(const RibbonLink& link, size_t ribbons) {
  const auto in_range = [&](int r) { return r >= 0 && static_cast<size_t>(r) < ribbons; };
  return in_range(link.ribbon[0]) && in_range(link.ribbon[1]) && link.ribbon[0] != link.ribbon[1];
}

// E_link (Eq. 6) for every pair of linked ribbons.
void AddLinkTerms(const std::vector<RibbonLink>& links, size_t ribbons, double alpha,
                  std::vector<BinaryMrfPair>* pairs) {
  struct Entry {
    uint32_t a, b;
    bool needs_equal;
    int segment_a, segment_b;
  };
  std::vector<Entry> entries;
  for (const RibbonLink& link : links) {
    if (!ValidLink(link, ribbons)) continue;
    const bool swap = link.ribbon[0] > link.ribbon[1];
    entries.push_back({static_cast<uint32_t>(link.ribbon[swap ? 1 : 0]),
                       static_cast<uint32_t>(link.ribbon[swap ? 0 : 1]), NeedsEqualDirections(link),
                       link.segment[swap ? 1 : 0], link.segment[swap ? 0 : 1]});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return std::tie(x.a, x.b, x.needs_equal) < std::tie(y.a, y.b, y.needs_equal);
  });
  // Per ribbon pair, Psi of the links that equal and that different directions would break.
  std::vector<BinaryMrfPair> strengths;
  for (size_t k = 0; k < entries.size();) {
    BinaryMrfPair pair{entries[k].a, entries[k].b, 0, 0};
    while (k < entries.size() && entries[k].a == pair.a && entries[k].b == pair.b) {
      const bool needs_equal = entries[k].needs_equal;
      std::vector<int> side_a, side_b;
      for (; k < entries.size() && entries[k].a == pair.a && entries[k].b == pair.b &&
             entries[k].needs_equal == needs_equal;
           ++k) {
        side_a.push_back(entries[k].segment_a);
        side_b.push_back(entries[k].segment_b);
      }
      (needs_equal ? pair.cost_differ : pair.cost_equal) = LinkStrength(side_a, side_b);
    }
    strengths.push_back(pair);
  }
  double largest = 0;
  for (const BinaryMrfPair& p : strengths)
    largest = std::max({largest, p.cost_equal, p.cost_differ});
  if (largest <= 0) return;
  for (BinaryMrfPair p : strengths) {
    p.cost_equal *= alpha / largest;
    p.cost_differ *= alpha / largest;
    pairs->push_back(p);
  }
}

PolylineVertexTable TabulateRibbons(const std::vector<const Ribbon*>& ribbons) {
  PolylineVertexTable table;
  for (const Ribbon* r : ribbons) {
    table.StartOwner();
    for (const Curve& curve : r->isocurves) table.Append(curve);
  }
  table.Close();
  return table;
}

// E_close (Eq. 7) for every pair of overlapping ribbons.
void AddCloseTerms(const std::vector<Ribbon>& ribbons, const RibbonDirectionOptions& o,
                   std::vector<BinaryMrfPair>* pairs, int64_t* count) {
  std::vector<const Ribbon*> all;
  for (const Ribbon& r : ribbons) all.push_back(&r);
  for (const OwnerOverlap& overlap :
       FindOwnerOverlaps(TabulateRibbons(all), o.overlap_mm, 1, o.threads)) {
    if (overlap.votes == 0) continue;
    const double cost = o.alpha_close * overlap.share;
    // Orientations that agree where they overlap are compatible with equal directions.
    pairs->push_back(
        {overlap.a, overlap.b, overlap.votes > 0 ? 0.0 : cost, overlap.votes > 0 ? cost : 0.0});
    ++*count;
  }
}

// One term per ribbon pair: the terms of each pair summed.
void MergeTerms(std::vector<BinaryMrfPair>* pairs) {
  std::sort(pairs->begin(), pairs->end(), [](const BinaryMrfPair& x, const BinaryMrfPair& y) {
    return std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  size_t out = 0;
  for (size_t k = 0; k < pairs->size(); ++k) {
    BinaryMrfPair& last = (*pairs)[out == 0 ? 0 : out - 1];
    if (out > 0 && last.a == (*pairs)[k].a && last.b == (*pairs)[k].b) {
      last.cost_equal += (*pairs)[k].cost_equal;
      last.cost_differ += (*pairs)[k].cost_differ;
    } else {
      (*pairs)[out++] = (*pairs)[k];
    }
  }
  pairs->resize(out);
}

// Reverses the l direction of the ribbons labelled 1 and the parameters of
// the links at them.
void ReverseRibbons(const std::vector<uint8_t>& reverse, std::vector<Ribbon>* ribbons,
                    std::vector<RibbonLink>* links) {
  for (size_t r = 0; r < ribbons->size(); ++r) {
    if (!reverse[r]) continue;
    for (Curve& curve : (*ribbons)[r].isocurves) std::reverse(curve.begin(), curve.end());
  }
  for (RibbonLink& link : *links) {
    if (!ValidLink(link, ribbons->size())) continue;
    for (int k = 0; k < 2; ++k) {
      const size_t r = static_cast<size_t>(link.ribbon[k]);
      if (!reverse[r]) continue;
      link.link_point[k].l = static_cast<float>((*ribbons)[r].length()) - link.link_point[k].l;
      link.link_point[k].orientation = -link.link_point[k].orientation;
      link.segment_along_ribbon[k] = !link.segment_along_ribbon[k];
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------

RibbonCoordinates ProjectOntoRibbon(const Ribbon& ribbon, const Eigen::Vector3f& p) {
  SurfacePoint best;
  if (ribbon.isocurves.empty() || ribbon.isocurves[0].empty()) return ToCoordinates(best, p, 0);
  // The cells around the nearest vertex first, so that most others are skipped.
  GridIndex nearest{0, 0};
  float nearest2 = std::numeric_limits<float>::max();
  for (int j = 0; j <= ribbon.width(); ++j) {
    for (int i = 0; i <= ribbon.length(); ++i) {
      const float d2 =
          (ribbon.isocurves[static_cast<size_t>(j)][static_cast<size_t>(i)] - p).squaredNorm();
      if (d2 < nearest2) nearest2 = d2, nearest = {j, i};
    }
  }
  ProjectOnCells(ribbon.isocurves,
                 CellsAround(ribbon.isocurves, 0, ribbon.width(), nearest.j, nearest.i), p, &best);
  ProjectOnCells(ribbon.isocurves, AllCells(ribbon.isocurves, 0, ribbon.width()), p, &best, true);
  return ToCoordinates(best, p, 0);
}

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

Status ConnectionOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(max_end_gap_mm))
    return InvalidArgument("connection max_end_gap_mm must be positive");
  if (fit_vertices < 3) return InvalidArgument("connection fit_vertices must be at least 3");
  if (!positive(max_rms_mm)) return InvalidArgument("connection max_rms_mm must be positive");
  if (!positive(max_curvature_ratio))
    return InvalidArgument("connection max_curvature_ratio must be positive");
  if (!(max_normal_angle_deg >= 0 && max_normal_angle_deg <= 180)) {
    return InvalidArgument("connection max_normal_angle_deg must lie in 0..180");
  }
  if (!(max_overlap >= 0 && max_overlap <= 1))
    return InvalidArgument("connection max_overlap must lie in 0..1");
  if (!positive(straight_radius_mm))
    return InvalidArgument("connection straight_radius_mm must be positive");
  if (!(min_gap_cos >= -1 && min_gap_cos < 1))
    return InvalidArgument("connection min_gap_cos must lie in [-1, 1)");
  if (threads < 1) return InvalidArgument("connection threads must be at least 1");
  return Status::Ok();
}

std::vector<RibbonLink> ConnectRibbons(const std::vector<Ribbon>& ribbons,
                                       const std::vector<StrandSegment>& segments,
                                       const ConnectionOptions& options,
                                       ConnectionSummary* summary) {
  ConnectionSummary s;
  std::vector<int> ribbon_of(segments.size(), -1);
  for (size_t r = 0; r < ribbons.size(); ++r) {
    for (int seg : ribbons[r].segments) {
      if (seg >= 0 && static_cast<size_t>(seg) < segments.size() &&
          ribbon_of[static_cast<size_t>(seg)] < 0) {
        ribbon_of[static_cast<size_t>(seg)] = static_cast<int>(r);
      }
    }
  }
  const std::vector<SegmentEnd> ends = FitEnds(segments, ribbon_of, options);
  const std::vector<EndVerdicts> verdicts = JudgePairs(ends, options);
  RibbonProjector projector(ribbons);
  std::vector<int> along(segments.size(), -1);  // per segment, AlongRibbon once asked (0/1)
  const auto along_ribbon = [&](const SegmentEnd& e) {
    int& known = along[static_cast<size_t>(e.segment)];
    if (known < 0)
      known = projector.AlongRibbon(e.ribbon, segments[static_cast<size_t>(e.segment)].points_mm)
                  ? 1
                  : 0;
    return known == 1;
  };
  std::vector<RibbonLink> links;
  for (size_t e = 0; e < ends.size(); ++e) {
    AddCounts(verdicts[e], &s);
    for (const EndVerdicts::Accepted& accepted : verdicts[e].accepted) {
      RibbonLink link;
      for (int k = 0; k < 2; ++k) {
        const SegmentEnd& end = ends[k == 0 ? e : accepted.partner];
        link.ribbon[k] = end.ribbon;
        link.segment[k] = end.segment;
        link.link_point[k] = projector.Project(end.ribbon, end.position);
        link.at_first_vertex[k] = end.at_first;
        link.segment_along_ribbon[k] = along_ribbon(end);
      }
      link.rms_mm = accepted.rms_mm;
      link.radius_mm = accepted.radius_mm;
      links.push_back(link);
    }
  }
  if (summary != nullptr) *summary = s;
  return links;
}

double RibbonOverlap(const Ribbon& a, const Ribbon& b, double overlap_mm, bool* compatible) {
  if (compatible != nullptr) *compatible = true;
  if (!(overlap_mm > 0)) return 0;
  const std::vector<OwnerOverlap> overlaps =
      FindOwnerOverlaps(TabulateRibbons({&a, &b}), overlap_mm, 1, 1);
  if (overlaps.empty()) return 0;
  if (compatible != nullptr) *compatible = overlaps[0].votes >= 0;
  return overlaps[0].share;
}

Status RibbonDirectionOptions::Check() const {
  if (!(height_scale_mm > 0))
    return InvalidArgument("ribbon direction height_scale_mm must be positive");
  if (!(alpha_link >= 0) || !(alpha_close >= 0))
    return InvalidArgument("ribbon direction weights must be non-negative");
  if (!(overlap_mm > 0)) return InvalidArgument("ribbon direction overlap_mm must be positive");
  if (threads < 1) return InvalidArgument("ribbon direction threads must be at least 1");
  if (!(std::abs(down.norm() - 1) < 1e-3))
    return InvalidArgument("ribbon direction down must be a unit vector");
  return Status::Ok();
}

RibbonDirectionSummary DirectRibbons(std::vector<Ribbon>* ribbons, std::vector<RibbonLink>* links,
                                     const HeadModel* head, const RibbonDirectionOptions& options) {
  RibbonDirectionSummary summary;
  const size_t n = ribbons->size();
  summary.ribbons = static_cast<int64_t>(n);
  summary.links = static_cast<int64_t>(links->size());
  if (n == 0) return summary;

  // Label 0: D(R) = 0 -> L; label 1: L -> 0.
  BinaryMrf mrf;
  const ScalpDistance zeta(head);
  for (const Ribbon& r : *ribbons) {
    const double keep = RibbonEnergy(r, zeta, options);
    mrf.unary.push_back({keep, -keep});
  }
  AddLinkTerms(*links, n, options.alpha_link, &mrf.pairs);
  AddCloseTerms(*ribbons, options, &mrf.pairs, &summary.overlapping_pairs);
  MergeTerms(&mrf.pairs);
  const BinaryMrfSolution solution = SolveBinaryMrf(mrf);
  summary.energy = solution.energy;
  summary.truncated_pairs = solution.truncated_pairs;

  ReverseRibbons(solution.labels, ribbons, links);
  summary.reversed = std::count(solution.labels.begin(), solution.labels.end(), 1);
  // Every ribbon now runs 0 -> L: a link is compatible when it needs equal directions.
  const auto incompatible = [n](const RibbonLink& link) {
    return !ValidLink(link, n) || !NeedsEqualDirections(link);
  };
  summary.incompatible_links = std::count_if(links->begin(), links->end(), incompatible);
  summary.compatible_links = summary.links - summary.incompatible_links;
  links->erase(std::remove_if(links->begin(), links->end(), incompatible), links->end());
  return summary;
}

}  // namespace hairrig
