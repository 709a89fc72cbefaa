#include "reconstruction/wisp_attachment.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "reconstruction/strand_segments.h"
#include "reconstruction/wisp_grid.h"

namespace hairrig {

namespace {

constexpr int kFixedRootVertices = 3;  // r and the two vertices after it along d_g
constexpr int kGaussNewtonRounds = 3;

Eigen::Vector3f UnitOr(const Eigen::Vector3f& v, const Eigen::Vector3f& fallback) {
  return v.norm() > 1e-6f ? Eigen::Vector3f(v.normalized()) : fallback;
}

Eigen::Vector3f Tangent(const std::vector<Eigen::Vector3f>& curve, size_t i) {
  const size_t before = i == 0 ? 0 : i - 1, after = std::min(i + 1, curve.size() - 1);
  return UnitOr(curve[after] - curve[before], Eigen::Vector3f::UnitZ());
}

// v made perpendicular to the unit t, unit; `fallback` (made perpendicular
// too) when v is (nearly) along t.
Eigen::Vector3f PerpendicularUnit(const Eigen::Vector3f& v, const Eigen::Vector3f& t,
                                  const Eigen::Vector3f& fallback) {
  const Eigen::Vector3f p = v - v.dot(t) * t;
  if (p.norm() > 1e-3f * std::max(v.norm(), 1e-6f)) return p.normalized();
  return UnitOr(fallback - fallback.dot(t) * t, t.unitOrthogonal());
}

}  // namespace

WispAttacher::WispAttacher(const HeadModel& head, const ScalpGuide& guide,
                           const InteriorField& field, const WispOptions& options,
                           double bounding_diagonal_mm)
    : head_(head),
      guide_(guide),
      field_(field),
      options_(options),
      field_weight_(options.interior_weight * bounding_diagonal_mm) {}

Eigen::Vector3f WispAttacher::KeepOutside(const Eigen::Vector3f& v, double margin_mm) const {
  return head_.KeepOutside(v.cast<double>(), margin_mm).cast<float>();
}

std::vector<Eigen::Vector3f> WispAttacher::InteriorStrand(
    const ScalpRoot& root, const Eigen::Vector3f& q, const Eigen::Vector3f* continuation) const {
  const float step = static_cast<float>(options_.step_mm);
  const Eigen::Vector3f& r = root.position;
  if ((q - r).norm() <= 3 * step) return {r, q};
  std::vector<Eigen::Vector3f> initial = {r, r + step * root.growing_direction,
                                          r + 2 * step * root.growing_direction};
  const Eigen::Vector3f from = initial.back();
  const int steps = std::max(1, static_cast<int>(std::ceil((q - from).norm() / step)));
  for (int k = 1; k <= steps; ++k)
    initial.push_back(from + (q - from) * (static_cast<float>(k) / static_cast<float>(steps)));
  const int n = static_cast<int>(initial.size());  // q is vertex n - 1
  for (int i = kFixedRootVertices; i + 1 < n; ++i)
    initial[i] = KeepOutside(initial[i], options_.head_clearance_mm);
  if (continuation != nullptr) initial.push_back(*continuation);

  PolylineSmoothing smoothing;
  smoothing.alpha_position = options_.smooth_position;
  smoothing.alpha_orientation = options_.smooth_orientation;
  smoothing.alpha_curvature = options_.smooth_curvature;
  smoothing.fixed.assign(initial.size(), 1);
  for (int i = kFixedRootVertices; i + 1 < n; ++i) smoothing.fixed[i] = 0;
  // Eq. 13, alpha_int B (i / N - I(p_i))^2, linearised about the current positions.
  std::vector<Eigen::Vector3f> current = initial;
  for (int round = 0; round < kGaussNewtonRounds; ++round) {
    std::vector<VertexFieldTerm> terms;
    for (int i = kFixedRootVertices; i + 1 < n; ++i) {
      const Eigen::Vector3f gradient = field_.Gradient(current[i]);
      const double target =
          static_cast<double>(i) / (n - 1) - field_.At(current[i]) + gradient.dot(current[i]);
      terms.push_back({i, gradient, target, field_weight_});
    }
    current = SmoothPolyline(initial, smoothing, terms);
  }
  current.resize(static_cast<size_t>(n));
  for (int i = kFixedRootVertices; i + 1 < n; ++i)
    current[i] = KeepOutside(current[i], options_.head_clearance_mm);
  return current;
}

Eigen::Vector3f WispAttacher::PlaceOffsetVertex(int k, const Eigen::Vector3f& v) const {
  if (k == 0) return guide_.OntoSurface(v);
  return KeepOutside(v, k < kFixedRootVertices ? 0.0 : options_.head_clearance_mm);
}

bool WispAttacher::Attach(Wisp* wisp, std::mt19937_64& rng) const {
  if (wisp->isocurves.empty() || wisp->isocurves[0].empty()) return false;
  const std::vector<Eigen::Vector3f>& centre = wisp->center();
  const Eigen::Vector3f q = centre[0];
  if (!q.allFinite()) return false;
  const Eigen::Vector3f* continuation = centre.size() > 1 ? &centre[1] : nullptr;
  const std::vector<Eigen::Vector3f> strand = InteriorStrand(
      guide_.AssignRoot(q, options_.step_mm, options_.root_jitter_mm, rng), q, continuation);
  const int n = static_cast<int>(strand.size());  // strand.back() is q
  const size_t centre_index = wisp->isocurves.size() / 2;
  for (size_t j = 0; j < wisp->isocurves.size(); ++j) {
    std::vector<Eigen::Vector3f>& isocurve = wisp->isocurves[j];
    const Eigen::Vector3f offset = isocurve[0] - q;
    std::vector<Eigen::Vector3f> prefix(strand.begin(), strand.end() - 1);
    if (j != centre_index) {
      for (int k = 0; k + 1 < n; ++k) {
        const double share =
            options_.root_width_share + (1 - options_.root_width_share) * k / (n - 1);
        prefix[k] = PlaceOffsetVertex(k, strand[k] + static_cast<float>(share) * offset);
      }
    }
    isocurve.insert(isocurve.begin(), prefix.begin(), prefix.end());
  }
  wisp->interior_vertices = n;
  wisp->attached = true;
  return true;
}

bool WispAttacher::MakeInteriorWisp(const Eigen::Vector3f& target, std::mt19937_64& rng,
                                    Wisp* wisp) const {
  std::vector<Eigen::Vector3f> strand = InteriorStrand(
      guide_.AssignRoot(target, options_.step_mm, options_.root_jitter_mm, rng), target);
  size_t keep = strand.size();
  for (size_t i = kFixedRootVertices; i < strand.size(); ++i) {
    if (field_.At(strand[i]) > options_.interior_truncate_level) {
      keep = i;
      break;
    }
  }
  if (keep < kFixedRootVertices + 1) return false;
  strand.resize(keep);
  const int width = options_.interior_width;
  const float spacing = static_cast<float>(options_.spacing_mm);
  *wisp = Wisp{};
  wisp->isocurves.assign(static_cast<size_t>(width) + 1, std::vector<Eigen::Vector3f>(keep));
  for (size_t i = 0; i < keep; ++i) {
    const Eigen::Vector3f t = Tangent(strand, i);
    Eigen::Vector3d outward;
    head_.SignedDistance(strand[i].cast<double>(), &outward);
    const Eigen::Vector3f normal =
        PerpendicularUnit(field_.Gradient(strand[i]), t, outward.cast<float>());
    const Eigen::Vector3f across = t.cross(normal).normalized();
    for (int j = 0; j <= width; ++j) {
      const float offset = (static_cast<float>(j) - 0.5f * static_cast<float>(width)) * spacing;
      const Eigen::Vector3f v = strand[i] + offset * across;
      wisp->isocurves[static_cast<size_t>(j)][i] =
          offset == 0 ? v : PlaceOffsetVertex(static_cast<int>(i), v);
    }
  }
  wisp->range_low.assign(keep, 0.0f);
  wisp->range_high.assign(keep, static_cast<float>(width));
  wisp->interior = wisp->attached = true;
  wisp->interior_vertices = static_cast<int>(keep);
  return true;
}

void SetWispNormals(const HeadModel& head, std::vector<Wisp>* wisps) {
  for (Wisp& wisp : *wisps) {
    const int width = wisp.width(), length = wisp.length();
    const int c = width / 2;
    wisp.normals.assign(static_cast<size_t>(std::max(length + 1, 0)), Eigen::Vector3f::UnitZ());
    for (int i = 0; i <= length; ++i) {
      const Eigen::Vector3f along = IsocurvePoint(wisp.isocurves, c, std::min(i + 1, length)) -
                                    IsocurvePoint(wisp.isocurves, c, std::max(i - 1, 0));
      const Eigen::Vector3f across = IsocurvePoint(wisp.isocurves, std::min(c + 1, width), i) -
                                     IsocurvePoint(wisp.isocurves, std::max(c - 1, 0), i);
      const Eigen::Vector3f t = UnitOr(along, Eigen::Vector3f::UnitZ());
      Eigen::Vector3d outward_d;
      head.SignedDistance(
          wisp.isocurves[static_cast<size_t>(c)][static_cast<size_t>(i)].cast<double>(),
          &outward_d);
      const Eigen::Vector3f outward = outward_d.cast<float>();
      Eigen::Vector3f n = across.cross(along);
      n = n.norm() > 1e-6f * std::max(across.norm() * along.norm(), 1e-12f)
              ? Eigen::Vector3f(n.normalized())
              : PerpendicularUnit(outward, t, outward);
      wisp.normals[static_cast<size_t>(i)] = n.dot(outward) < 0 ? Eigen::Vector3f(-n) : n;
    }
  }
}

}  // namespace hairrig
