#include "simulation/floating_tangents.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/transform.h"
#include "simulation/strand_spline.h"

namespace hairrig {

namespace {
constexpr double kRadToDeg = 180 / kPi;
}  // namespace

Status FloatingTangentsOptions::Check() const {
  if (min_elements < 1 || max_elements < min_elements) {
    return InvalidArgument("element counts need 1 <= min_elements <= max_elements, got " +
                           std::to_string(min_elements) + " and " + std::to_string(max_elements));
  }
  if (!adaptive && fixed_elements < 1) return InvalidArgument("fixed_elements must be at least 1");
  if (!(min_length_mm > 0) || !(max_length_mm > min_length_mm) || !std::isfinite(max_length_mm))
    return InvalidArgument("lengths need 0 < min_length_mm < max_length_mm, both finite");
  if (!(target_mean_error_mm >= 0) || !std::isfinite(target_mean_error_mm))
    return InvalidArgument("target_mean_error_mm must be 0 (off) or positive");
  if (!(straight_sagitta_mm >= 0) || !std::isfinite(straight_sagitta_mm))
    return InvalidArgument("straight_sagitta_mm must be 0 (off) or positive");
  if (!(error_sagitta_mm > 0) || !std::isfinite(error_sagitta_mm))
    return InvalidArgument("error_sagitta_mm must be positive");
  return Status::Ok();
}

double PiecewiseHelix::length_mm() const {
  double total = 0;
  for (const auto& e : elements) total += e.length_mm;
  return total;
}

std::vector<Eigen::Vector3d> PiecewiseHelix::Sample(double step_mm) const {
  std::vector<Eigen::Vector3d> out;
  for (const auto& e : elements) {
    const int n = std::max(1, static_cast<int>(std::ceil(e.length_mm / step_mm)));
    for (int k = out.empty() ? 0 : 1; k <= n; ++k) out.push_back(e.PointAt(e.length_mm * k / n));
  }
  return out;
}

// Sec. V-A: N_min below L_min, N_max above L_max, else Algorithm 2.
int AdaptiveElementCount(const StrandSpline& spline, const FloatingTangentsOptions& o) {
  const double length = spline.length_mm();
  if (length < o.min_length_mm) return o.min_elements;
  if (length > o.max_length_mm) return o.max_elements;
  const int initial = (o.min_elements + o.max_elements) / 2;
  int n = initial;
  Eigen::Vector3d previous = spline.TangentAt(0);
  for (int i = 1; i <= initial; ++i) {
    const Eigen::Vector3d t = spline.TangentAt(length * i / initial);
    const double inner = previous.dot(t);
    if (inner <= 0) ++n;
    if (inner > 0.95) --n;
    previous = t;
  }
  return std::clamp(n, o.min_elements, o.max_elements);
}

namespace {

// Sec. V-B, Eqs. 4-5: each pair of consecutive break points must be
// co-helical, (p*_{j+1} - p*_j) . (t_{j+1} - t_j) = 0 (Eq. 3); when the
// tangents are equal the element must be straight, so the chord has no
// component across t_j (two conditions). Ours: an element flagged planar
// also has no chord component along the binormal (t_{j+1} - t_j) x (t_j +
// t_{j+1}), so it becomes a planar arc.
struct CohelicalCondition {
  int element = 0;
  Eigen::Vector3d normal;  // the chord's component along it must vanish
};

std::vector<CohelicalCondition> CohelicalConditions(const std::vector<Eigen::Vector3d>& t,
                                                    const std::vector<char>& planar) {
  std::vector<CohelicalCondition> rows;
  for (int j = 0; j + 1 < static_cast<int>(t.size()); ++j) {
    const Eigen::Vector3d& t0 = t[static_cast<size_t>(j)];
    const Eigen::Vector3d dt = t[static_cast<size_t>(j + 1)] - t0;
    if (dt.norm() < kStraightTangentGap) {
      const Eigen::Vector3d u = t0.unitOrthogonal();
      rows.push_back({j, u});
      rows.push_back({j, t0.cross(u).normalized()});
      continue;
    }
    const Eigen::Vector3d n = dt.normalized();
    rows.push_back({j, n});
    const Eigen::Vector3d sum = t0 + t[static_cast<size_t>(j + 1)];
    if (planar[static_cast<size_t>(j)] && sum.norm() > 1e-12)
      rows.push_back({j, n.cross(sum).normalized()});
  }
  return rows;
}

// A symmetric positive definite band matrix (half-bandwidth b) with its
// Cholesky factorisation in place: O(m b^2).
class BandCholesky {
 public:
  BandCholesky(int size, int bandwidth)
      : m_(size),
        b_(bandwidth),
        a_(static_cast<size_t>(size) * static_cast<size_t>(bandwidth + 1), 0.0) {}
  double& at(int row, int col) {  // row >= col, row - col <= b
    return a_[static_cast<size_t>(row) * static_cast<size_t>(b_ + 1) +
              static_cast<size_t>(row - col)];
  }
  // False if the matrix is not (numerically) positive definite.
  bool Factor() {
    for (int j = 0; j < m_; ++j) {
      for (int i = j; i < std::min(m_, j + b_ + 1); ++i) {
        double sum = at(i, j);
        for (int k = std::max(0, i - b_); k < j; ++k) sum -= at(i, k) * at(j, k);
        if (i == j) {
          if (!(sum > 1e-12)) return false;
          at(j, j) = std::sqrt(sum);
        } else {
          at(i, j) = sum / at(j, j);
        }
      }
    }
    return true;
  }
  void Solve(std::vector<double>* x) {
    std::vector<double>& v = *x;
    for (int i = 0; i < m_; ++i) {
      for (int k = std::max(0, i - b_); k < i; ++k)
        v[static_cast<size_t>(i)] -= at(i, k) * v[static_cast<size_t>(k)];
      v[static_cast<size_t>(i)] /= at(i, i);
    }
    for (int i = m_ - 1; i >= 0; --i) {
      for (int k = i + 1; k < std::min(m_, i + b_ + 1); ++k)
        v[static_cast<size_t>(i)] -= at(k, i) * v[static_cast<size_t>(k)];
      v[static_cast<size_t>(i)] /= at(i, i);
    }
  }

 private:
  int m_, b_;
  std::vector<double> a_;
};

// min sum_{i >= 0} |p*_i - p_i|^2 under the conditions C p* = 0 is the
// orthogonal projection p* = p - C^T (C C^T)^-1 C p. Each condition touches
// two neighbouring points, so C C^T is banded (rows of neighbouring elements
// only): O(N) to build and to solve. Dense LDL^T if the band factorisation
// fails (dependent conditions).
std::vector<Eigen::Vector3d> ProjectOntoConditions(const std::vector<Eigen::Vector3d>& p,
                                                   const std::vector<CohelicalCondition>& rows) {
  const int m = static_cast<int>(rows.size());
  // Entry (r, q) of C C^T for q >= r within the band; the visitor gets each one.
  auto for_each_entry = [&](auto&& visit) {
    for (int r = 0; r < m; ++r) {
      const CohelicalCondition& a = rows[static_cast<size_t>(r)];
      for (int q = r; q < m && rows[static_cast<size_t>(q)].element <= a.element + 1; ++q) {
        const CohelicalCondition& b = rows[static_cast<size_t>(q)];
        const double dot = a.normal.dot(b.normal);
        visit(r, q, b.element == a.element ? 2 * dot : -dot);
      }
    }
  };
  int bandwidth = 0;
  for_each_entry([&](int r, int q, double) { bandwidth = std::max(bandwidth, q - r); });
  std::vector<double> lambda(static_cast<size_t>(m));
  for (int r = 0; r < m; ++r) {
    const CohelicalCondition& a = rows[static_cast<size_t>(r)];
    lambda[static_cast<size_t>(r)] =
        a.normal.dot(p[static_cast<size_t>(a.element) + 1] - p[static_cast<size_t>(a.element)]);
  }
  BandCholesky band(m, bandwidth);
  for_each_entry([&](int r, int q, double value) { band.at(q, r) = value; });
  if (band.Factor()) {
    band.Solve(&lambda);
  } else {
    Eigen::MatrixXd cct = Eigen::MatrixXd::Zero(m, m);
    for_each_entry([&](int r, int q, double value) { cct(r, q) = cct(q, r) = value; });
    const Eigen::VectorXd solved = cct.ldlt().solve(Eigen::Map<Eigen::VectorXd>(lambda.data(), m));
    for (int r = 0; r < m; ++r) lambda[static_cast<size_t>(r)] = solved[r];
  }
  std::vector<Eigen::Vector3d> relaxed = p;
  for (int r = 0; r < m; ++r) {
    const CohelicalCondition& a = rows[static_cast<size_t>(r)];
    relaxed[static_cast<size_t>(a.element) + 1] -= lambda[static_cast<size_t>(r)] * a.normal;
    relaxed[static_cast<size_t>(a.element)] += lambda[static_cast<size_t>(r)] * a.normal;
  }
  return relaxed;
}

// Ours (anchor_root): the projection of all break points, the root included,
// onto the co-helical conditions. An element the strand crosses with little
// turning (`gentle`) whose relaxed pair no short rotation joins (its chord
// leans too far for the tangents' small turn: only a coil would fit) is made
// a planar arc and the projection repeated, at most a few times.
std::vector<Eigen::Vector3d> ProjectOntoCohelical(const std::vector<Eigen::Vector3d>& p,
                                                  const std::vector<Eigen::Vector3d>& t,
                                                  const std::vector<char>& gentle) {
  std::vector<char> planar(t.size(), 0);
  std::vector<Eigen::Vector3d> relaxed = ProjectOntoConditions(p, CohelicalConditions(t, planar));
  for (int pass = 0; !gentle.empty() && pass < 4; ++pass) {
    bool changed = false;
    for (size_t j = 0; j + 1 < t.size(); ++j) {
      if (!gentle[j] || planar[j] || (t[j + 1] - t[j]).norm() < kStraightTangentGap) continue;
      if (!ShortRotationExists(relaxed[j + 1] - relaxed[j], t[j], t[j + 1]))
        planar[j] = changed = true;
    }
    if (!changed) break;
    relaxed = ProjectOntoConditions(p, CohelicalConditions(t, planar));
  }
  return relaxed;
}

// Eq. 5 as printed (the sum from i = 1, p*_0 free): p*_i = p*_0 + sum_{j<i}
// D_j a_j with D_j a basis of the plane normal to t_{j+1} - t_j (the direction
// t_j itself when the tangents are equal), a linear least-squares solve in
// (p*_0, a_0, ..., a_{N-1}); the minimum-norm choice fixes the free p*_0.
std::vector<Eigen::Vector3d> RelaxBreakPoints(const std::vector<Eigen::Vector3d>& p,
                                              const std::vector<Eigen::Vector3d>& t,
                                              bool anchor_root, const std::vector<char>& gentle) {
  if (anchor_root) return ProjectOntoCohelical(p, t, gentle);
  const int n = static_cast<int>(p.size()) - 1;
  std::vector<Eigen::MatrixXd> basis(static_cast<size_t>(n));
  int unknowns = 3;
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d dt = t[static_cast<size_t>(j + 1)] - t[static_cast<size_t>(j)];
    if (dt.norm() < kStraightTangentGap) {
      basis[static_cast<size_t>(j)] = t[static_cast<size_t>(j)];
    } else {
      const Eigen::Vector3d normal = dt.normalized();
      Eigen::Vector3d v0 = (t[static_cast<size_t>(j)] + t[static_cast<size_t>(j + 1)]);
      v0 = v0.norm() > 1e-9 ? v0.normalized() : normal.unitOrthogonal();
      v0 = (v0 - v0.dot(normal) * normal).normalized();
      Eigen::Matrix<double, 3, 2> d;
      d << v0, normal.cross(v0);
      basis[static_cast<size_t>(j)] = d;
    }
    unknowns += static_cast<int>(basis[static_cast<size_t>(j)].cols());
  }
  const int first = anchor_root ? 0 : 1;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * (n + 1 - first), unknowns);
  Eigen::VectorXd b(3 * (n + 1 - first));
  for (int i = first; i <= n; ++i) {
    const int row = 3 * (i - first);
    a.block<3, 3>(row, 0).setIdentity();
    int col = 3;
    for (int j = 0; j < n; ++j) {
      const auto& d = basis[static_cast<size_t>(j)];
      if (j < i) a.block(row, col, 3, d.cols()) = d;
      col += static_cast<int>(d.cols());
    }
    b.segment<3>(row) = p[static_cast<size_t>(i)];
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
  std::vector<Eigen::Vector3d> relaxed{x.head<3>()};
  int col = 3;
  for (int j = 0; j < n; ++j) {
    const auto& d = basis[static_cast<size_t>(j)];
    relaxed.push_back(relaxed.back() + d * x.segment(col, d.cols()));
    col += static_cast<int>(d.cols());
  }
  return relaxed;
}

}  // namespace

namespace {

// Squared distance from q to the polyline segments [first, last) of `curve`,
// if below best2; `nearest` is then set to that segment.
double SquaredDistanceToSegments(const Eigen::Vector3d& q,
                                 const std::vector<Eigen::Vector3d>& curve, size_t first,
                                 size_t last, double best2, size_t* nearest) {
  for (size_t k = first; k < last; ++k) {
    const Eigen::Vector3d seg = curve[k + 1] - curve[k];
    const Eigen::Vector3d to_q = q - curve[k];
    const double len2 = seg.squaredNorm();
    const double u = len2 > 0 ? std::clamp(to_q.dot(seg) / len2, 0.0, 1.0) : 0.0;
    const double d2 = (to_q - u * seg).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      *nearest = k;
    }
  }
  return best2;
}

}  // namespace

// Exact, with pruning: the curve is cut into blocks of segments, each with a
// bounding sphere; a block is scanned only if its sphere can hold a point
// nearer than the best so far. The points follow the curve, so a few
// segments around the previous point's nearest one give a close first bound
// and most blocks are pruned.
void DistanceToCurve(const std::vector<Eigen::Vector3d>& points,
                     const std::vector<Eigen::Vector3d>& curve, double* mean_mm, double* max_mm) {
  constexpr size_t kWindow = 2;
  const size_t segments = curve.size() > 1 ? curve.size() - 1 : 0;
  // About sqrt(segments) blocks of sqrt(segments) segments: as many sphere
  // tests per point as segment tests in a block it cannot prune.
  const size_t block =
      std::max<size_t>(4, static_cast<size_t>(std::sqrt(static_cast<double>(segments))));
  std::vector<Eigen::Vector3d> centers;
  std::vector<double> radii;
  for (size_t first = 0; first < segments; first += block) {
    const size_t last = std::min(segments, first + block);
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    for (size_t k = first; k <= last; ++k) center += curve[k];
    center /= static_cast<double>(last - first + 1);
    double radius = 0;
    for (size_t k = first; k <= last; ++k) radius = std::max(radius, (curve[k] - center).norm());
    centers.push_back(center);
    radii.push_back(radius);
  }
  double sum = 0, worst = 0;
  size_t nearest = 0;
  for (const Eigen::Vector3d& q : points) {
    double best2 = (curve[0] - q).squaredNorm();
    if (segments > 0) {
      const size_t window_first = nearest > kWindow ? nearest - kWindow : 0;
      const size_t window_last = std::min(segments, nearest + kWindow + 1);
      best2 = SquaredDistanceToSegments(q, curve, window_first, window_last, best2, &nearest);
      double best = std::sqrt(best2);
      for (size_t b = 0; b < centers.size(); ++b) {
        const double reach = radii[b] + best;
        if ((q - centers[b]).squaredNorm() >= reach * reach) continue;
        best2 = SquaredDistanceToSegments(q, curve, b * block,
                                          std::min(segments, b * block + block), best2, &nearest);
        best = std::sqrt(best2);
      }
    }
    const double best = std::sqrt(best2);
    sum += best;
    worst = std::max(worst, best);
  }
  *mean_mm = points.empty() ? 0 : sum / static_cast<double>(points.size());
  *max_mm = worst;
}

namespace {

// Elements over which the strand's tangent turns by less than kGentleTurn
// (radians, summed over quarters of the element): there a short rotation,
// not a coil, is the helix that follows the strand.
std::vector<char> GentleElements(const StrandSpline& spline, int n) {
  constexpr double kGentleTurn = 0.5;
  constexpr int kQuarters = 4;
  const double step = spline.length_mm() / (n * kQuarters);
  std::vector<char> gentle(static_cast<size_t>(n));
  Eigen::Vector3d previous = spline.TangentAt(0);
  for (int j = 0; j < n; ++j) {
    double turn = 0;
    for (int q = 1; q <= kQuarters; ++q) {
      const Eigen::Vector3d next = spline.TangentAt(step * (j * kQuarters + q));
      turn += (next - previous).norm();  // the chord of the turn: at most the angle
      previous = next;
    }
    gentle[static_cast<size_t>(j)] = turn < kGentleTurn;
  }
  return gentle;
}

// Ours (straight_sagitta_mm): a run of elements of length h each whose
// tangents stay within 8 s / (run length) of the run's first tangent (an
// arc turning by that angle strays s from its chord) shares that tangent, so
// its elements are straight. Unit tangents in, unit tangents out.
void StraightenRuns(double element_length_mm, double sagitta_mm, std::vector<Eigen::Vector3d>* t) {
  if (!(sagitta_mm > 0)) return;
  std::vector<Eigen::Vector3d>& tangent = *t;
  double run_length = 0;
  for (size_t j = 0; j + 1 < tangent.size(); ++j) {
    run_length += element_length_mm;
    if ((tangent[j + 1] - tangent[j]).norm() * run_length < 8 * sagitta_mm) {
      tangent[j + 1] = tangent[j];
    } else {
      run_length = 0;
    }
  }
}

// The mean and max distance from the strand's points to the helical curve,
// as a polyline whose chords stray at most `sagitta_mm` from it.
void MeasureFitError(const StrandSpline& spline, const PiecewiseHelix& model, double sagitta_mm,
                     StrandFitSummary* s) {
  std::vector<Eigen::Vector3d> curve{model.elements.front().start_mm};
  for (const auto& e : model.elements) {
    // A chord of length h on a curve of curvature k strays k h^2 / 8 from it
    // (at most 64 chords per turn about the helix axis, a wild coil's bound).
    const double chords = e.length_mm * std::sqrt(e.curvature_per_mm() / (8 * sagitta_mm));
    const double turns = e.darboux_per_mm.norm() * e.length_mm / (2 * M_PI);
    const double cap = 64 * std::ceil(std::max(1.0, turns));
    e.AppendSamples(std::max(2, static_cast<int>(std::ceil(std::min(chords, cap)))), &curve);
  }
  DistanceToCurve(spline.points(), curve, &s->mean_error_mm, &s->max_error_mm);
}

// What a fit measures besides the model: nothing, the fit error alone (for
// ours' growth) or everything in StrandFitSummary.
enum class Measures { kNone, kError, kAll };

// Algorithm 1, lines 4-7: N + 1 break points at equal arc length with their
// tangents, relaxed to be co-helical.
struct BreakPoints {
  std::vector<Eigen::Vector3d> p, t, relaxed;
  double max_relaxation_elements = 0;  // the largest |p*_i - p_i|, in elements
};
BreakPoints RelaxedBreakPoints(const StrandSpline& spline, int n,
                               const FloatingTangentsOptions& options) {
  const double length = spline.length_mm();
  BreakPoints b;
  for (int i = 0; i <= n; ++i) {
    b.p.push_back(spline.PointAt(length * i / n));
    b.t.push_back(spline.TangentAt(length * i / n));
  }
  StraightenRuns(length / n, options.straight_sagitta_mm, &b.t);
  b.relaxed =
      RelaxBreakPoints(b.p, b.t, options.anchor_root,
                       options.planar_arcs ? GentleElements(spline, n) : std::vector<char>{});
  for (int i = 0; i <= n; ++i) {
    b.max_relaxation_elements = std::max(
        b.max_relaxation_elements,
        (b.relaxed[static_cast<size_t>(i)] - b.p[static_cast<size_t>(i)]).norm() * n / length);
  }
  return b;
}

// Algorithm 1, line 8, for the break points of a given element count.
Result<PiecewiseHelix> FitWithElementCount(const StrandSpline& spline, const BreakPoints& b,
                                           const FloatingTangentsOptions& options,
                                           Measures measures, StrandFitSummary* summary) {
  const double length = spline.length_mm();
  const int n = static_cast<int>(b.p.size()) - 1;
  const std::vector<Eigen::Vector3d>& p = b.p;
  const std::vector<Eigen::Vector3d>& t = b.t;
  const std::vector<Eigen::Vector3d>& relaxed = b.relaxed;
  PiecewiseHelix model;
  StrandFitSummary s;
  s.max_relaxation_elements = b.max_relaxation_elements;
  double axis_angle = -1;  // each element's helix search starts from the previous one's
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d chord =
        relaxed[static_cast<size_t>(i + 1)] - relaxed[static_cast<size_t>(i)];
    const Eigen::Vector3d dt = t[static_cast<size_t>(i + 1)] - t[static_cast<size_t>(i)];
    if (measures == Measures::kAll && chord.norm() > 0)
      s.max_cohelical_residual =
          std::max(s.max_cohelical_residual, std::abs(chord.dot(dt)) / chord.norm());
    // The preferred length: the strand's arc between the break points,
    // stretched as the relaxation stretched their chord.
    const double original_chord =
        (p[static_cast<size_t>(i + 1)] - p[static_cast<size_t>(i)]).norm();
    const double preferred =
        original_chord > 0 ? length / n * chord.norm() / original_chord : length / n;
    auto element = HelixThrough(relaxed[static_cast<size_t>(i)], t[static_cast<size_t>(i)],
                                relaxed[static_cast<size_t>(i + 1)], t[static_cast<size_t>(i + 1)],
                                preferred, &axis_angle);
    if (!element.ok()) {
      return Internal("floating tangents: element " + std::to_string(i) + " of " +
                      std::to_string(n) + ": " + element.status().message());
    }
    model.elements.push_back(*element);
  }
  for (int i = 0; measures == Measures::kAll && i + 1 < n; ++i) {
    const auto& e = model.elements[static_cast<size_t>(i)];
    const double c = std::clamp(
        e.TangentAt(e.length_mm).dot(model.elements[static_cast<size_t>(i + 1)].start_tangent),
        -1.0, 1.0);
    s.max_g1_defect_deg = std::max(s.max_g1_defect_deg, std::acos(c) * kRadToDeg);
  }
  s.elements = n;
  s.strand_length_mm = length;
  if (measures != Measures::kNone) MeasureFitError(spline, model, options.error_sagitta_mm, &s);
  *summary = s;
  return model;
}

}  // namespace

Result<PiecewiseHelix> FitFloatingTangents(const std::vector<Eigen::Vector3d>& points_mm,
                                           const FloatingTangentsOptions& options,
                                           StrandFitSummary* summary) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("floating tangents options"));
  HR_ASSIGN_OR_RETURN(StrandSpline spline, StrandSpline::Create(points_mm));
  int n = options.adaptive ? AdaptiveElementCount(spline, options) : options.fixed_elements;
  if (options.adaptive && options.target_mean_error_mm > 0) {
    // Ours: no element need turn by more than a right angle, the turn at
    // which Algorithm 2 adds an element (<t_i, t_i+1> <= 0).
    constexpr double kRightAngle = M_PI / 2;
    const int quarter_turns = static_cast<int>(std::ceil(spline.turning_rad() / kRightAngle));
    n = std::max(n, std::min(quarter_turns, options.max_elements));
  }
  // Everything is measured when the caller asks for a summary; otherwise the
  // fit error only when the growth below needs it.
  const bool grows = options.adaptive && options.target_mean_error_mm > 0;
  auto measures = [&](int elements) {
    return summary                                    ? Measures::kAll
           : grows && elements < options.max_elements ? Measures::kError
                                                      : Measures::kNone;
  };
  // Ours: a relaxation that moves a break point by more than a quarter of an
  // element is a resonance, not a fit. Elements of about half a curl make
  // consecutive co-helical conditions (Eq. 3) constrain nearly the same
  // direction, so a strand that is not an exact helix is shifted along it
  // more with every element (10 mm over 25 elements on curly 40 cm strands,
  // where one element fewer relaxes by 1 mm). At N_max, where the growth
  // ends whatever the error, one element fewer is taken if it relaxes less.
  // Measured on the bench's 5,000 curly 40 cm strands: mean error 0.78 ->
  // 0.63 mm, max 16.4 -> 8.5 mm; the other sets within 0.5 % or better.
  constexpr double kResonantRelaxation = 0.25;  // elements
  auto break_points = [&](int elements) {
    BreakPoints b = RelaxedBreakPoints(spline, elements, options);
    if (grows && elements == options.max_elements && elements > options.min_elements &&
        b.max_relaxation_elements > kResonantRelaxation) {
      BreakPoints fewer = RelaxedBreakPoints(spline, elements - 1, options);
      if (fewer.max_relaxation_elements < b.max_relaxation_elements) return fewer;
    }
    return b;
  };
  StrandFitSummary s;
  HR_ASSIGN_OR_RETURN(PiecewiseHelix model,
                      FitWithElementCount(spline, break_points(n), options, measures(n), &s));
  // Ours beside Algorithm 2: more elements while the fit error exceeds the
  // target, aimed straight at it by the error law e ~ N^-k. k starts at 2
  // (measured on the bench's strands: 1.9 from N = 3 to 15; a cubic law
  // undershot and cost a third fit) and is then taken from the last two
  // fits, within [1, 4]. N grows by at least a quarter each time.
  double exponent = 2;
  while (grows && s.mean_error_mm > options.target_mean_error_mm && n < options.max_elements) {
    const double predicted =
        n * std::pow(s.mean_error_mm / options.target_mean_error_mm, 1 / exponent);
    const int previous_n = n;
    const double previous_error = s.mean_error_mm;
    n = std::min(options.max_elements,
                 std::max(n + std::max(1, n / 4), static_cast<int>(std::ceil(predicted))));
    HR_ASSIGN_OR_RETURN(model,
                        FitWithElementCount(spline, break_points(n), options, measures(n), &s));
    if (s.mean_error_mm > 0 && previous_error > s.mean_error_mm) {
      exponent = std::clamp(std::log(previous_error / s.mean_error_mm) /
                                std::log(static_cast<double>(n) / previous_n),
                            1.0, 4.0);
    }
  }
  if (summary) *summary = s;
  return model;
}

}  // namespace hairrig
