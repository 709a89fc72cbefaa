// Internal to the ribbons of reconstruction/ribbons.h: what their parts
// share. ribbons_projection.cpp projects points onto a ribbon's tessellated
// grid (R^{-1} of Luo et al. 2013 Sec. 5.2, ProjectOntoRibbon);
// ribbons_cover.cpp grows the ribbons over the segments (Sec. 5.2,
// CoverWithRibbons); ribbons_connect.cpp links them (Sec. 6.1,
// ConnectRibbons); ribbons_direction.cpp directs them (Sec. 6.2,
// RibbonOverlap, DirectRibbons). Shared here: the grid's types, the
// projection onto a range of its cells and a hash grid over a ribbon's
// vertices that finds where to project.
//
// Units mm, the points' frame. Nothing here fails: a search that finds no
// vertex returns false, and a projection that finds no point leaves the
// distance at +infinity.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "reconstruction/ribbons.h"

namespace hairrig {
namespace detail {

using Curve = std::vector<Eigen::Vector3f>;
using Curves = std::vector<Curve>;

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The best candidate so far; w counts isocurves from curves[0].
struct SurfacePoint {
  double distance2 = kInfinity;
  float w = 0, l = 0;
  Eigen::Vector3f closest = Eigen::Vector3f::Zero(), orientation = Eigen::Vector3f::Zero();
};

// A grid vertex: vertex i of isocurve j.
struct GridIndex {
  int j, i;
};

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
                    SurfacePoint* best, bool skip_far_cells = false);

// The (up to four) cells that share vertex (j, i), within isocurves lo..hi.
CellRange CellsAround(const Curves& curves, int lo, int hi, int j, int i);

// `s`, the projection of p, as RibbonCoordinates with w counted from isocurve
// `w_offset` of the curves; closest is p itself when nothing was found.
RibbonCoordinates ToCoordinates(const SurfacePoint& s, const Eigen::Vector3f& p, int w_offset);

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

}  // namespace detail
}  // namespace hairrig
