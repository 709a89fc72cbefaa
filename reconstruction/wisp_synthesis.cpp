// Sec. 7.3: the wisps' ranges (Eq. 14) and the strands synthesised in them.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "reconstruction/strand_segments.h"
#include "reconstruction/wisp_grid.h"
#include "reconstruction/wisps.h"

namespace hairrig {

namespace {

constexpr float kUnset = std::numeric_limits<float>::infinity();

struct RawRanges {
  std::vector<float> low, high;  // per i; +inf / -inf where no point covers
};

// The nearest vertex of each wisp near a point: (grid, vertex, squared distance).
struct NearestVertex {
  uint32_t grid, vertex;
  double distance2;
};

// Eq. 14 over every point: the covered points' w bounds per rounded l.
int64_t AccumulateRanges(const std::vector<OrientedPoint>& points, const WispOptions& o,
                         const std::vector<const Isocurves*>& grids,
                         std::vector<RawRanges>* ranges) {
  const double reach =
      o.spacing_mm +
      o.step_mm;  // a point within spacing of a quad is this close to one of its corners
  const GridVertexIndex index(grids, reach);
  int64_t covered_points = 0;
  std::vector<NearestVertex> nearest;
  for (const OrientedPoint& point : points) {
    nearest.clear();
    index.points().ForEachWithin(point.position_mm, reach, [&](uint32_t vertex, double d2) {
      const uint32_t grid = index.owner(vertex).grid;
      const auto known = std::find_if(nearest.begin(), nearest.end(),
                                      [&](const NearestVertex& n) { return n.grid == grid; });
      if (known == nearest.end()) {
        nearest.push_back({grid, vertex, d2});
      } else if (d2 < known->distance2) {
        known->vertex = vertex, known->distance2 = d2;
      }
    });
    bool covers = false;
    for (const NearestVertex& n : nearest) {
      const GridVertexIndex::Owner& owner = index.owner(n.vertex);
      const GridProjection projection = ProjectNearVertex(
          *grids[n.grid], static_cast<int>(owner.j), static_cast<int>(owner.i), point.position_mm);
      if (projection.distance_mm > o.spacing_mm ||
          std::abs(projection.along.dot(point.direction)) < o.cover_cos)
        continue;
      RawRanges& r = (*ranges)[n.grid];
      const size_t l = static_cast<size_t>(std::lround(projection.l));
      r.low[l] = std::min(r.low[l], projection.w);
      r.high[l] = std::max(r.high[l], projection.w);
      covers = true;
    }
    covered_points += covers ? 1 : 0;
  }
  return covered_points;
}

// The curve g minimising sum over known i (g_i - y_i)^2 + lambda sum
// (g_{i+1} - g_i)^2: smoothed where known, linear across gaps, constant past
// the ends. `values` holds y_i or a non-finite value where unknown; at least
// one is known and lambda > 0. A tridiagonal solve (Thomas).
std::vector<float> SmoothOverGaps(const std::vector<float>& values, double lambda) {
  const size_t n = values.size();
  std::vector<double> diagonal(n), upper(n, -lambda), rhs(n);
  for (size_t i = 0; i < n; ++i) {
    const bool known = std::isfinite(values[i]);
    const int neighbours = (i > 0 ? 1 : 0) + (i + 1 < n ? 1 : 0);
    diagonal[i] = (known ? 1.0 : 0.0) + lambda * neighbours;
    rhs[i] = known ? values[i] : 0.0;
  }
  for (size_t i = 1; i < n; ++i) {  // forward elimination; the sub-diagonal is -lambda too
    const double m = -lambda / diagonal[i - 1];
    diagonal[i] -= m * upper[i - 1];
    rhs[i] -= m * rhs[i - 1];
  }
  std::vector<float> g(n);
  double next = 0;
  for (size_t k = n; k-- > 0;) {
    next = (rhs[k] - (k + 1 < n ? upper[k] * next : 0.0)) / diagonal[k];
    g[k] = static_cast<float>(next);
  }
  return g;
}

// The quadratic tapering factor towards the tip (1 before taper_start).
void Taper(const WispOptions& o, std::vector<float>* low, std::vector<float>* high) {
  const size_t n = low->size();
  if (n < 2 || o.taper_start >= 1) return;
  for (size_t i = 0; i < n; ++i) {
    const double x =
        (static_cast<double>(i) / static_cast<double>(n - 1) - o.taper_start) / (1 - o.taper_start);
    if (x <= 0) continue;
    const double factor = 1 - (1 - o.tip_range_share) * x * x;
    const double middle = 0.5 * ((*low)[i] + (*high)[i]), half = 0.5 * ((*high)[i] - (*low)[i]);
    (*low)[i] = static_cast<float>(middle - factor * half);
    (*high)[i] = static_cast<float>(middle + factor * half);
  }
}

void FinishRanges(const WispOptions& o, const RawRanges* raw, Wisp* wisp) {
  const size_t n = static_cast<size_t>(wisp->length() + 1);
  const float width = static_cast<float>(wisp->width());
  const bool from_points = raw != nullptr && std::any_of(raw->low.begin(), raw->low.end(),
                                                         [](float v) { return std::isfinite(v); });
  if (!from_points) {
    wisp->range_low.assign(n, 0.0f);
    wisp->range_high.assign(n, width);
  } else {
    std::vector<float> low = raw->low, high = raw->high;
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(low[i])) low[i] = high[i] = std::numeric_limits<float>::quiet_NaN();
    }
    wisp->range_low = SmoothOverGaps(low, o.range_smoothness);
    wisp->range_high = SmoothOverGaps(high, o.range_smoothness);
    for (size_t i = 0; i < n; ++i) {
      float& lo = wisp->range_low[i];
      float& hi = wisp->range_high[i];
      lo = std::clamp(lo, 0.0f, width), hi = std::clamp(hi, 0.0f, width);
      if (lo > hi) lo = hi = 0.5f * (lo + hi);
    }
  }
  Taper(o, &wisp->range_low, &wisp->range_high);
}

// g-(i), g+(i), or [0, W] where the ranges are missing.
void RangeAt(const Wisp& wisp, size_t i, float* low, float* high) {
  const bool has = wisp.range_low.size() == wisp.isocurves[0].size() &&
                   wisp.range_high.size() == wisp.range_low.size();
  *low = has ? wisp.range_low[i] : 0.0f;
  *high = has ? wisp.range_high[i] : static_cast<float>(wisp.width());
}

// The width (isocurves, plus one) times the length (mm) of a wisp's ranges.
double RangeArea(const Wisp& wisp) {
  if (wisp.isocurves.empty() || wisp.length() < 1) return 0;
  const std::vector<Eigen::Vector3f>& centre = wisp.center();
  double area = 0;
  for (size_t i = 0; i + 1 < centre.size(); ++i) {
    float low0, high0, low1, high1;
    RangeAt(wisp, i, &low0, &high0);
    RangeAt(wisp, i + 1, &low1, &high1);
    area += (0.5 * (high0 - low0 + high1 - low1) + 1) * (centre[i + 1] - centre[i]).norm();
  }
  return area;
}

// `total` split in proportion to the weights, largest remainders first.
std::vector<int> Apportion(const std::vector<double>& weights, int total) {
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  std::vector<int> counts(weights.size(), 0);
  if (!(sum > 0) || total <= 0) return counts;
  std::vector<std::pair<double, size_t>> remainders;
  int given = 0;
  for (size_t k = 0; k < weights.size(); ++k) {
    const double share = total * weights[k] / sum;
    counts[k] = static_cast<int>(std::floor(share));
    given += counts[k];
    remainders.emplace_back(share - counts[k], k);
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t r = 0; given < total && r < remainders.size(); ++r, ++given)
    ++counts[remainders[r].second];
  return counts;
}

std::vector<Eigen::Vector3f> StrandInWisp(const Wisp& wisp, double t, double thickness_mm,
                                          const SynthesisOptions& o) {
  const size_t n = wisp.isocurves[0].size();
  const bool has_normals = wisp.normals.size() == n;
  std::vector<Eigen::Vector3f> strand(n);
  double arc_mm = 0;
  Eigen::Vector3f previous = Eigen::Vector3f::Zero();
  for (size_t i = 0; i < n; ++i) {
    float low, high;
    RangeAt(wisp, i, &low, &high);
    const Eigen::Vector3f on_wisp =
        IsocurvePoint(wisp.isocurves, low * (1 - t) + high * t, static_cast<int>(i));
    if (i > 0) arc_mm += (on_wisp - previous).norm();
    previous = on_wisp;
    const double ramp = o.thickness_ramp_mm > 0 ? std::min(1.0, arc_mm / o.thickness_ramp_mm) : 1.0;
    strand[i] =
        has_normals
            ? Eigen::Vector3f(on_wisp - static_cast<float>(thickness_mm * ramp) * wisp.normals[i])
            : on_wisp;
  }
  PolylineSmoothing smoothing;
  smoothing.alpha_position = o.smooth_position;
  smoothing.alpha_orientation = o.smooth_orientation;
  smoothing.alpha_curvature = o.smooth_curvature;
  smoothing.fixed.assign(n, 0);
  smoothing.fixed[0] = 1;  // the root stays where the wisp has it (on the scalp)
  return SmoothPolyline(strand, smoothing);
}

}  // namespace

int64_t SetWispRanges(const std::vector<OrientedPoint>& points, const WispOptions& options,
                      std::vector<Wisp>* wisps) {
  std::vector<const Isocurves*> grids;
  std::vector<size_t> wisp_of_grid;
  std::vector<RawRanges> raw;
  for (size_t k = 0; k < wisps->size(); ++k) {
    const Wisp& wisp = (*wisps)[k];
    if (wisp.interior || wisp.isocurves.empty() || wisp.isocurves[0].empty()) continue;
    grids.push_back(&wisp.isocurves);
    wisp_of_grid.push_back(k);
    const size_t n = wisp.isocurves[0].size();
    raw.push_back({std::vector<float>(n, kUnset), std::vector<float>(n, -kUnset)});
  }
  const int64_t covered = grids.empty() ? 0 : AccumulateRanges(points, options, grids, &raw);
  std::vector<const RawRanges*> raw_of_wisp(wisps->size(), nullptr);
  for (size_t g = 0; g < grids.size(); ++g) raw_of_wisp[wisp_of_grid[g]] = &raw[g];
  for (size_t k = 0; k < wisps->size(); ++k) {
    if (!(*wisps)[k].isocurves.empty()) FinishRanges(options, raw_of_wisp[k], &(*wisps)[k]);
  }
  return covered;
}

Status SynthesisOptions::Check() const {
  if (!(thickness_mm >= 0)) return InvalidArgument("synthesis thickness_mm must be non-negative");
  if (!(thickness_ramp_mm >= 0))
    return InvalidArgument("synthesis thickness_ramp_mm must be non-negative");
  if (!(smooth_position > 0) || !(smooth_orientation >= 0) || !(smooth_curvature >= 0)) {
    return InvalidArgument(
        "synthesis smoothing weights: position must be positive, the others non-negative");
  }
  return Status::Ok();
}

StrandSet SynthesizeStrands(const std::vector<Wisp>& wisps, int strands, uint64_t seed,
                            const SynthesisOptions& o) {
  std::vector<double> areas(wisps.size());
  for (size_t k = 0; k < wisps.size(); ++k) areas[k] = RangeArea(wisps[k]);
  const std::vector<int> counts = Apportion(areas, strands);
  StrandSet set;
  for (size_t k = 0; k < wisps.size(); ++k) {
    std::mt19937_64 rng(seed + 0x9E3779B97F4A7C15ull * (k + 1));
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int s = 0; s < counts[k]; ++s) {
      const double t = (s + uniform(rng)) / counts[k];  // stratified across the ranges
      const double thickness = std::max(o.thickness_mm, 0.0) * uniform(rng);
      set.AddStrand(StrandInWisp(wisps[k], t, thickness, o));
    }
  }
  return set;
}

}  // namespace hairrig
