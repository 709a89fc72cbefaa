// Projection onto a ribbon's tessellated grid (R^{-1} of Sec. 5.2):
// ProjectOntoRibbon (reconstruction/ribbons.h) and the projection onto
// ranges of grid cells the other ribbon steps share
// (reconstruction/ribbons_internal.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "reconstruction/polyline_overlap.h"
#include "reconstruction/ribbons.h"
#include "reconstruction/ribbons_internal.h"

namespace hairrig {
namespace detail {
namespace {

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

}  // namespace

void ProjectOnCells(const Curves& curves, const CellRange& range, const Eigen::Vector3f& p,
                    SurfacePoint* best, bool skip_far_cells) {
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

}  // namespace detail

using detail::CellRange;
using detail::CellsAround;
using detail::Curves;
using detail::GridIndex;
using detail::ProjectOnCells;
using detail::SurfacePoint;
using detail::ToCoordinates;

namespace {

// Every cell of isocurves lo..hi.
CellRange AllCells(const Curves& curves, int lo, int hi) {
  const int length = static_cast<int>(curves[static_cast<size_t>(lo)].size()) - 1;
  return {lo, hi, lo, std::max(lo + 1, hi), 0, std::max(1, length)};
}

}  // namespace

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

}  // namespace hairrig
