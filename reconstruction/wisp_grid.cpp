#include "reconstruction/wisp_grid.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace hairrig {

namespace {

struct Corner {
  Eigen::Vector3f position;
  float w, l;
};

// The point of segment ab closest to p, as the weight of b.
float SegmentParameter(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                       const Eigen::Vector3f& b) {
  const Eigen::Vector3f ab = b - a;
  const float length2 = ab.squaredNorm();
  return length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0f, 1.0f) : 0.0f;
}

// Barycentric weights of the point of triangle abc closest to p.
Eigen::Vector3f ClosestBarycentric(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                   const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f normal = (b - a).cross(c - a);
  const float area2 = normal.squaredNorm();
  if (area2 > 1e-12f) {
    const Eigen::Vector3f in_plane = p - normal * (normal.dot(p - a) / area2);
    const float wa = (c - b).cross(in_plane - b).dot(normal) / area2;
    const float wb = (a - c).cross(in_plane - c).dot(normal) / area2;
    const float wc = 1 - wa - wb;
    if (wa >= 0 && wb >= 0 && wc >= 0) return {wa, wb, wc};
  }
  // Outside (or degenerate): the nearest of the three edges.
  const Eigen::Vector3f* corners[3] = {&a, &b, &c};
  Eigen::Vector3f best_weights(1, 0, 0);
  float best2 = std::numeric_limits<float>::max();
  for (int k = 0; k < 3; ++k) {
    const int next = (k + 1) % 3;
    const float t = SegmentParameter(p, *corners[k], *corners[next]);
    const float d2 = ((1 - t) * *corners[k] + t * *corners[next] - p).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best_weights.setZero();
      best_weights[k] = 1 - t;
      best_weights[next] = t;
    }
  }
  return best_weights;
}

void KeepCloser(const Eigen::Vector3f& p, const Corner& a, const Corner& b, const Corner& c,
                const Eigen::Vector3f& along, GridProjection* best) {
  const Eigen::Vector3f weights = ClosestBarycentric(p, a.position, b.position, c.position);
  const Eigen::Vector3f closest =
      weights[0] * a.position + weights[1] * b.position + weights[2] * c.position;
  const float distance = (closest - p).norm();
  if (distance >= best->distance_mm) return;
  best->distance_mm = distance;
  best->w = weights[0] * a.w + weights[1] * b.w + weights[2] * c.w;
  best->l = weights[0] * a.l + weights[1] * b.l + weights[2] * c.l;
  best->along = along;
}

Eigen::Vector3f UnitOr(const Eigen::Vector3f& v, const Eigen::Vector3f& fallback) {
  return v.norm() > 1e-9f ? Eigen::Vector3f(v.normalized()) : fallback;
}

}  // namespace

Eigen::Vector3f IsocurvePoint(const Isocurves& grid, double w, int i) {
  const int width = static_cast<int>(grid.size()) - 1;
  const double clamped = std::clamp(w, 0.0, static_cast<double>(width));
  const int j = std::min(static_cast<int>(clamped), std::max(width - 1, 0));
  const float f = static_cast<float>(clamped - j);
  if (width == 0 || f <= 0) return grid[static_cast<size_t>(j)][static_cast<size_t>(i)];
  return (1 - f) * grid[static_cast<size_t>(j)][static_cast<size_t>(i)] +
         f * grid[static_cast<size_t>(j) + 1][static_cast<size_t>(i)];
}

GridVertexIndex::GridVertexIndex(const std::vector<const Isocurves*>& grids, double cell_mm) {
  for (size_t g = 0; g < grids.size(); ++g) {
    const Isocurves& grid = *grids[g];
    for (size_t j = 0; j < grid.size(); ++j)
      for (size_t i = 0; i < grid[j].size(); ++i) {
        positions_.push_back(grid[j][i]);
        owners_.push_back(
            {static_cast<uint32_t>(g), static_cast<uint32_t>(j), static_cast<uint32_t>(i)});
      }
  }
  grid_ = std::make_unique<PointGrid>(positions_, cell_mm);
}

GridProjection ProjectNearVertex(const Isocurves& grid, int j, int i, const Eigen::Vector3f& p) {
  const int width = static_cast<int>(grid.size()) - 1;
  const int length = static_cast<int>(grid[0].size()) - 1;
  const auto corner = [&](int cj, int ci) {
    return Corner{grid[static_cast<size_t>(cj)][static_cast<size_t>(ci)], static_cast<float>(cj),
                  static_cast<float>(ci)};
  };
  GridProjection best;
  best.distance_mm = std::numeric_limits<float>::max();
  best.w = static_cast<float>(j);
  best.l = static_cast<float>(i);
  if (length == 0) {
    best.distance_mm = (grid[static_cast<size_t>(j)][0] - p).norm();
    return best;
  }
  for (int i0 = std::max(i - 1, 0); i0 <= std::min(i, length - 1); ++i0) {
    if (width == 0) {
      const Corner a = corner(0, i0), b = corner(0, i0 + 1);
      const Eigen::Vector3f along = UnitOr(b.position - a.position, Eigen::Vector3f::UnitZ());
      KeepCloser(p, a, b, b, along, &best);
      continue;
    }
    for (int j0 = std::max(j - 1, 0); j0 <= std::min(j, width - 1); ++j0) {
      const Corner c00 = corner(j0, i0), c10 = corner(j0 + 1, i0), c11 = corner(j0 + 1, i0 + 1),
                   c01 = corner(j0, i0 + 1);
      const Eigen::Vector3f along = UnitOr(
          (c01.position - c00.position) + (c11.position - c10.position), Eigen::Vector3f::UnitZ());
      KeepCloser(p, c00, c10, c11, along, &best);
      KeepCloser(p, c00, c11, c01, along, &best);
    }
  }
  return best;
}

}  // namespace hairrig
