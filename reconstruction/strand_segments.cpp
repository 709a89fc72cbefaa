#include "reconstruction/strand_segments.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.h"
#include "reconstruction/point_segment_distance.h"

namespace hairrig {

namespace {

enum class Stop { kTurn, kHole, kMls, kLength };

// Grows from `start` along `direction` (one side of Sec. 5.1's growing); the
// vertices after `start`.
std::vector<Eigen::Vector3f> GrowOneWay(const PointOrientationField& field,
                                        const PointSetSurface& surface,
                                        const Eigen::Vector3f& start, Eigen::Vector3f direction,
                                        const SegmentGrowthOptions& o, Stop* why) {
  std::vector<Eigen::Vector3f> grown;
  Eigen::Vector3f p = start;
  *why = Stop::kLength;
  for (int step = 0; step < o.max_steps; ++step) {
    const Eigen::Vector3f moved = p + direction * static_cast<float>(o.step_mm);
    Eigen::Vector3f projected, normal;
    if (!surface.Project(moved, &projected, &normal, o.min_neighbours)) {
      *why = Stop::kHole;
      break;
    }
    const Eigen::Vector3f shift = projected - moved;
    if (shift.norm() > o.mls_min_shift_mm &&
        std::abs(shift.normalized().dot(direction)) > o.max_mls_along) {
      *why = Stop::kMls;  // rule 3
      break;
    }
    Eigen::Vector3f next;
    if (!field.At(projected, direction, o.neighbour_cos, o.min_neighbours, &next)) {
      *why = Stop::kHole;  // rule 2
      break;
    }
    if (next.dot(direction) < o.min_turn_cos) {
      *why = Stop::kTurn;  // rule 1 (next is signed to agree with direction)
      break;
    }
    grown.push_back(projected);
    p = projected;
    direction = next;
  }
  return grown;
}

// Marks the seeds within `cover_mm` of the polyline.
void Cover(const PointGrid& grid, const std::vector<Eigen::Vector3f>& line, double cover_mm,
           std::vector<uint8_t>* covered) {
  const double cover2 = cover_mm * cover_mm;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector3f& a = line[i];
    const Eigen::Vector3f& b = line[i + 1];
    const Eigen::Vector3f mid = 0.5f * (a + b);
    const double reach = cover_mm + 0.5 * (b - a).norm();
    grid.ForEachWithin(mid, reach, [&](uint32_t k, double) {
      if (!(*covered)[k] && PointSegmentDistance2(grid.positions()[k], a, b) <= cover2)
        (*covered)[k] = 1;
    });
  }
  if (line.size() == 1) {
    grid.ForEachWithin(line[0], cover_mm, [&](uint32_t k, double) { (*covered)[k] = 1; });
  }
}

}  // namespace

Status SegmentGrowthOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(step_mm)) return InvalidArgument("segment step_mm must be positive");
  if (!positive(sigma_mm)) return InvalidArgument("segment sigma_mm must be positive");
  if (!(min_turn_cos >= 0 && min_turn_cos <= 1))
    return InvalidArgument("segment min_turn_cos must lie in 0..1");
  if (!(neighbour_cos >= 0 && neighbour_cos < 1))
    return InvalidArgument("segment neighbour_cos must lie in [0, 1)");
  if (!(max_mls_along > 0 && max_mls_along <= 1))
    return InvalidArgument("segment max_mls_along must lie in (0, 1]");
  if (min_neighbours < 1) return InvalidArgument("segment min_neighbours must be at least 1");
  if (!positive(cover_mm)) return InvalidArgument("segment cover_mm must be positive");
  if (!(smooth_position > 0) || !(smooth_orientation >= 0) || !(smooth_curvature >= 0)) {
    return InvalidArgument(
        "segment smoothing weights: position must be positive, the others non-negative");
  }
  if (!positive(split_height_mm))
    return InvalidArgument("segment split_height_mm must be positive");
  if (!(std::abs(down.norm() - 1) < 1e-3))
    return InvalidArgument("segment down must be a unit vector");
  if (!(mls_min_shift_mm >= 0))
    return InvalidArgument("segment mls_min_shift_mm must be non-negative");
  if (max_steps < 1) return InvalidArgument("segment max_steps must be at least 1");
  if (min_vertices < 2) return InvalidArgument("segment min_vertices must be at least 2");
  return Status::Ok();
}

double StrandSegment::Length() const {
  double length = 0;
  for (size_t i = 1; i < points_mm.size(); ++i) length += (points_mm[i] - points_mm[i - 1]).norm();
  return length;
}

std::vector<Eigen::Vector3f> SmoothPolyline(const std::vector<Eigen::Vector3f>& points,
                                            double alpha_position, double alpha_orientation,
                                            double alpha_curvature) {
  PolylineSmoothing smoothing;
  smoothing.alpha_position = alpha_position;
  smoothing.alpha_orientation = alpha_orientation;
  smoothing.alpha_curvature = alpha_curvature;
  return SmoothPolyline(points, smoothing);
}

namespace {

// Eq. 3's normal equations, Q p = b, one Q shared by x, y and z.
struct NormalEquations {
  std::vector<Eigen::Triplet<double>> q;
  Eigen::MatrixXd b;  // n x 3
};

NormalEquations Eq3NormalEquations(const std::vector<Eigen::Vector3f>& points,
                                   const PolylineSmoothing& o) {
  const int n = static_cast<int>(points.size());
  const bool own_edges = o.edges.size() == points.size() - 1;
  NormalEquations eq;
  eq.b = Eigen::MatrixXd::Zero(n, 3);
  const auto add = [&](int r, int c, double v) { eq.q.emplace_back(r, c, v); };
  for (int i = 0; i < n; ++i) {
    add(i, i, o.alpha_position);
    eq.b.row(i) += o.alpha_position * points[i].cast<double>().transpose();
  }
  for (int i = 0; i + 1 < n; ++i) {  // alpha1 |p_{i+1} - p_i - e_i|^2
    const Eigen::Vector3f edge =
        own_edges ? o.edges[i] : Eigen::Vector3f(points[i + 1] - points[i]);
    const Eigen::RowVector3d e = edge.cast<double>().transpose();
    add(i, i, o.alpha_orientation);
    add(i + 1, i + 1, o.alpha_orientation);
    add(i, i + 1, -o.alpha_orientation);
    add(i + 1, i, -o.alpha_orientation);
    eq.b.row(i + 1) += o.alpha_orientation * e;
    eq.b.row(i) -= o.alpha_orientation * e;
  }
  for (int i = 1; i + 1 < n; ++i) {  // alpha2 |p_{i-1} - 2 p_i + p_{i+1}|^2
    const int idx[3] = {i - 1, i, i + 1};
    const double coef[3] = {1, -2, 1};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) add(idx[a], idx[c], o.alpha_curvature * coef[a] * coef[c]);
  }
  return eq;
}

// Solves the symmetric positive definite system given by its entries
// (duplicates summed) for every column of `rhs` in place: LDL^T on band
// storage, O(size bandwidth^2), the bandwidth the entries' largest distance
// from the diagonal. False when a pivot is not positive.
bool SolveBanded(int size, const std::vector<Eigen::Triplet<double>>& entries,
                 Eigen::MatrixXd* rhs) {
  int b = 0;
  for (const Eigen::Triplet<double>& t : entries) b = std::max(b, std::abs(t.row() - t.col()));
  Eigen::MatrixXd band = Eigen::MatrixXd::Zero(size, b + 1);  // band(i, k) = A(i, i - k)
  for (const Eigen::Triplet<double>& t : entries) {
    if (t.row() >= t.col()) band(t.row(), t.row() - t.col()) += t.value();
  }
  // In place: band(i, 0) becomes D_i, band(i, k) becomes L(i, i - k).
  for (int i = 0; i < size; ++i) {
    for (int k = std::min(b, i); k >= 1; --k) {
      const int j = i - k;
      double value = band(i, k);
      for (int m = std::max(0, i - b); m < j; ++m)
        value -= band(i, i - m) * band(m, 0) * band(j, j - m);
      band(i, k) = value / band(j, 0);
    }
    double pivot = band(i, 0);
    for (int k = 1; k <= std::min(b, i); ++k) pivot -= band(i, k) * band(i, k) * band(i - k, 0);
    if (!(pivot > 0)) return false;
    band(i, 0) = pivot;
  }
  for (int c = 0; c < rhs->cols(); ++c) {
    auto x = rhs->col(c);
    for (int i = 0; i < size; ++i)
      for (int k = 1; k <= std::min(b, i); ++k) x(i) -= band(i, k) * x(i - k);
    for (int i = 0; i < size; ++i) x(i) /= band(i, 0);
    for (int i = size - 1; i >= 0; --i)
      for (int k = 1; k <= std::min(b, size - 1 - i); ++k) x(i) -= band(i + k, k) * x(i + k);
  }
  return true;
}

}  // namespace

std::vector<Eigen::Vector3f> SmoothPolyline(const std::vector<Eigen::Vector3f>& points,
                                            const PolylineSmoothing& smoothing,
                                            const std::vector<VertexFieldTerm>& field_terms) {
  const int n = static_cast<int>(points.size());
  if (n < 3) return points;
  const NormalEquations eq = Eq3NormalEquations(points, smoothing);
  const bool any_fixed = smoothing.fixed.size() == points.size();
  const auto is_fixed = [&](int i) { return any_fixed && smoothing.fixed[i] != 0; };
  // Fixed vertices leave the unknowns: their columns move to the right-hand
  // side and their rows become p_i = p_i^(0), which keeps the system symmetric.
  // Coordinates are interleaved (3 i + axis) when field terms couple them.
  const int axes = field_terms.empty() ? 1 : 3;
  const int size = n * axes;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs =
      Eigen::MatrixXd::Zero(size, 4 - axes);  // 3 columns, or 1 column of interleaved coordinates
  const auto rhs_at = [&](int vertex, int axis) -> double& {
    return axes == 1 ? rhs(vertex, axis) : rhs(3 * vertex + axis, 0);
  };
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) rhs_at(i, k) = is_fixed(i) ? points[i][k] : eq.b(i, k);
  for (const Eigen::Triplet<double>& t : eq.q) {
    const int r = t.row(), c = t.col();
    if (is_fixed(r)) continue;
    if (is_fixed(c)) {
      for (int k = 0; k < 3; ++k) rhs_at(r, k) -= t.value() * points[c][k];
      continue;
    }
    for (int k = 0; k < axes; ++k) entries.emplace_back(r * axes + k, c * axes + k, t.value());
  }
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < axes; ++k)
      if (is_fixed(i)) entries.emplace_back(i * axes + k, i * axes + k, 1.0);
  for (const VertexFieldTerm& term : field_terms) {
    if (term.vertex < 0 || term.vertex >= n || is_fixed(term.vertex)) continue;
    const Eigen::Vector3d g = term.gradient.cast<double>();
    for (int a = 0; a < 3; ++a) {
      rhs_at(term.vertex, a) += term.weight * term.target * g[a];
      for (int c = 0; c < 3; ++c) {
        entries.emplace_back(3 * term.vertex + a, 3 * term.vertex + c, term.weight * g[a] * g[c]);
      }
    }
  }
  Eigen::MatrixXd solved = rhs;
  if (!SolveBanded(size, entries, &solved)) return points;
  std::vector<Eigen::Vector3f> out(n);
  for (int i = 0; i < n; ++i) {
    out[i] = axes == 1 ? Eigen::Vector3f(solved.row(i).transpose().cast<float>())
                       : Eigen::Vector3f(solved.block<3, 1>(3 * i, 0).cast<float>());
  }
  return out;
}

std::vector<std::vector<Eigen::Vector3f>> SplitImplausible(
    const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& down,
    double split_height_mm) {
  constexpr double kHysteresisMm = 1.0;
  const size_t n = points.size();
  if (n < 3) return {points};
  std::vector<double> height(n);
  for (size_t i = 0; i < n; ++i) height[i] = points[i].dot(down);
  // Turning points: where the height's trend reverses by more than the hysteresis.
  std::vector<size_t> turns = {0};
  size_t extreme = 0;
  int trend = 0;
  for (size_t i = 1; i < n; ++i) {
    const double change = height[i] - height[extreme];
    if (trend == 0) {
      if (std::abs(change) > kHysteresisMm) trend = change > 0 ? 1 : -1, extreme = i;
      continue;
    }
    if ((trend > 0 && height[i] >= height[extreme]) ||
        (trend < 0 && height[i] <= height[extreme])) {
      extreme = i;
    } else if (std::abs(change) > kHysteresisMm) {
      turns.push_back(extreme);
      trend = -trend;
      extreme = i;
    }
  }
  turns.push_back(n - 1);
  std::vector<size_t> cuts;
  for (size_t k = 1; k + 1 < turns.size(); ++k) {
    const bool big_before = std::abs(height[turns[k]] - height[turns[k - 1]]) > split_height_mm;
    const bool big_after = std::abs(height[turns[k + 1]] - height[turns[k]]) > split_height_mm;
    if (big_before || big_after) cuts.push_back(turns[k]);
  }
  std::vector<std::vector<Eigen::Vector3f>> pieces;
  size_t begin = 0;
  for (size_t cut : cuts) {
    pieces.emplace_back(points.begin() + static_cast<std::ptrdiff_t>(begin),
                        points.begin() + static_cast<std::ptrdiff_t>(cut) + 1);
    begin = cut;
  }
  pieces.emplace_back(points.begin() + static_cast<std::ptrdiff_t>(begin), points.end());
  return pieces;
}

namespace {

// One seed's segment before covering: both ways grown, joined and smoothed
// (empty where the seed has no orientation).
struct GrownFromSeed {
  std::vector<Eigen::Vector3f> smooth;
  Stop why_back = Stop::kLength, why_forward = Stop::kLength;
};

GrownFromSeed GrowFromSeed(const PointOrientationField& field, const PointSetSurface& surface,
                           const Eigen::Vector3f& seed, const SegmentGrowthOptions& o) {
  GrownFromSeed grown;
  Eigen::Vector3f start = seed, projected, normal, t;
  if (surface.Project(start, &projected, &normal, o.min_neighbours)) start = projected;
  if (!field.At(start, Eigen::Vector3f::Zero(), 0, o.min_neighbours, &t)) return grown;
  std::vector<Eigen::Vector3f> back = GrowOneWay(field, surface, start, -t, o, &grown.why_back);
  const std::vector<Eigen::Vector3f> forward =
      GrowOneWay(field, surface, start, t, o, &grown.why_forward);
  std::reverse(back.begin(), back.end());
  back.push_back(start);
  back.insert(back.end(), forward.begin(), forward.end());
  grown.smooth = SmoothPolyline(back, o.smooth_position, o.smooth_orientation, o.smooth_curvature);
  return grown;
}

}  // namespace

std::vector<StrandSegment> GrowStrandSegments(const std::vector<OrientedPoint>& points,
                                              const SegmentGrowthOptions& o,
                                              SegmentGrowthSummary* summary) {
  SegmentGrowthSummary s;
  s.seeds = static_cast<int64_t>(points.size());
  const PointOrientationField field(points, o.sigma_mm);
  const PointSetSurface surface(field.grid(),
                                o.sigma_mm);  // the field's grid: same points, same 2 sigma cells
  std::vector<uint32_t> seeds(points.size());
  std::iota(seeds.begin(), seeds.end(), 0u);
  std::stable_sort(seeds.begin(), seeds.end(), [&](uint32_t a, uint32_t b) {
    return points[a].confidence > points[b].confidence;
  });
  std::vector<uint8_t> covered(points.size(), 0);
  std::vector<StrandSegment> segments;
  double total_length = 0;
  // Growing from a seed does not depend on what is covered, so the next
  // batch of uncovered seeds grows in parallel; their segments are then
  // taken in seed order, each only if no earlier one covered its seed: the
  // sequential algorithm's result, whatever the thread count.
  const int threads = ResolveThreads(o.threads);
  const size_t batch_size = 64 * static_cast<size_t>(threads);
  std::vector<uint32_t> batch;
  std::vector<GrownFromSeed> grown;
  size_t next_seed = 0;
  while (true) {
    batch.clear();
    for (; next_seed < seeds.size() && batch.size() < batch_size; ++next_seed) {
      if (!covered[seeds[next_seed]]) batch.push_back(seeds[next_seed]);
    }
    if (batch.empty()) break;
    grown.assign(batch.size(), GrownFromSeed{});
    ParallelFor(batch.size(), threads, [&] {
      return [&](size_t i) {
        grown[i] = GrowFromSeed(field, surface, points[batch[i]].position_mm, o);
      };
    });
    for (size_t i = 0; i < batch.size(); ++i) {
      if (covered[batch[i]]) continue;
      covered[batch[i]] = 1;
      ++s.seeds_grown;
      if (grown[i].smooth.empty()) continue;
      for (Stop why : {grown[i].why_back, grown[i].why_forward}) {
        ++(why == Stop::kTurn   ? s.stops_turn
           : why == Stop::kHole ? s.stops_hole
           : why == Stop::kMls  ? s.stops_mls
                                : s.stops_length);
      }
      Cover(field.grid(), grown[i].smooth, o.cover_mm, &covered);
      const auto pieces = SplitImplausible(grown[i].smooth, o.down, o.split_height_mm);
      s.splits += static_cast<int64_t>(pieces.size()) - 1;
      for (const auto& piece : pieces) {
        if (static_cast<int>(piece.size()) < o.min_vertices) continue;
        segments.push_back({piece});
        s.vertices += static_cast<int64_t>(piece.size());
        total_length += segments.back().Length();
      }
    }
  }
  s.segments = static_cast<int64_t>(segments.size());
  s.mean_length_mm = segments.empty() ? 0 : total_length / static_cast<double>(segments.size());
  if (summary != nullptr) *summary = s;
  return segments;
}

}  // namespace hairrig
