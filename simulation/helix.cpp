#include "simulation/helix.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <vector>

namespace hairrig {

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
}

Eigen::Vector3d HelixElement::PointAt(double s) const {
  const double w = darboux_per_mm.norm();
  if (w < 1e-15) return start_mm + s * start_tangent;
  const Eigen::Vector3d axis = darboux_per_mm / w;
  const double tau_bar = start_tangent.dot(axis);
  return start_mm + tau_bar * s * axis + std::sin(w * s) / w * (start_tangent - tau_bar * axis) -
         (1 - std::cos(w * s)) / w * start_tangent.cross(axis);
}

Eigen::Vector3d HelixElement::TangentAt(double s) const {
  const double w = darboux_per_mm.norm();
  if (w < 1e-15) return start_tangent;
  const Eigen::Vector3d axis = darboux_per_mm / w;
  const double tau_bar = start_tangent.dot(axis);
  return start_tangent + (std::cos(w * s) - 1) * (start_tangent - tau_bar * axis) -
         std::sin(w * s) * start_tangent.cross(axis);
}

double HelixElement::torsion_per_mm() const {
  const double w = darboux_per_mm.norm();
  return w < 1e-15 ? 0.0 : start_tangent.dot(darboux_per_mm / w) * w;
}

double HelixElement::curvature_per_mm() const {
  const double w = darboux_per_mm.norm();
  const double tau = torsion_per_mm();
  return std::sqrt(std::max(0.0, w * w - tau * tau));
}

// Omega = tau t + k b (Eq. 7) with b = t x n.
HelixElement HelixFromCurvatureTorsion(const Eigen::Vector3d& start_mm,
                                       const Eigen::Vector3d& tangent,
                                       const Eigen::Vector3d& normal, double curvature_per_mm,
                                       double torsion_per_mm, double length_mm) {
  HelixElement h;
  h.start_mm = start_mm;
  h.start_tangent = tangent.normalized();
  const Eigen::Vector3d binormal = h.start_tangent.cross(normal).normalized();
  h.darboux_per_mm = torsion_per_mm * h.start_tangent + curvature_per_mm * binormal;
  h.length_mm = length_mm;
  return h;
}

namespace {

// For a candidate axis of the helix (unit, orthogonal to t1 - t0): the
// rotation angle theta in (0, 2 pi] about it that takes t0 to t1, and
// g = w * (p1 - p0), the chord of the helix scaled by its angular rate.
struct AxisCandidate {
  Eigen::Vector3d axis;
  double theta = 0;
  Eigen::Vector3d scaled_chord;
  bool valid = false;
};

AxisCandidate EvaluateAxis(const Eigen::Vector3d& axis, const Eigen::Vector3d& t0,
                           const Eigen::Vector3d& t1, int extra_turns) {
  AxisCandidate c;
  c.axis = axis;
  const double tau_bar = t0.dot(axis);
  const Eigen::Vector3d u0 = t0 - tau_bar * axis;
  const Eigen::Vector3d u1 = t1 - t1.dot(axis) * axis;
  if (u0.norm() < 1e-12) return c;  // the tangent is along the axis: no rotation to speak of
  c.theta = std::atan2(axis.dot(u0.cross(u1)), u0.dot(u1));
  if (c.theta <= 0) c.theta += kTwoPi;
  c.theta += kTwoPi * extra_turns;
  c.scaled_chord =
      tau_bar * c.theta * axis + std::sin(c.theta) * u0 - (1 - std::cos(c.theta)) * t0.cross(axis);
  c.valid = true;
  return c;
}

}  // namespace

Result<HelixElement> HelixThrough(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0,
                                  const Eigen::Vector3d& p1, const Eigen::Vector3d& t1,
                                  double preferred_length_mm) {
  const Eigen::Vector3d chord = p1 - p0;
  const double chord_len = chord.norm();
  if (!(chord_len > 1e-12) || !chord.allFinite())
    return InvalidArgument("helix: the two points coincide or are not finite");
  if (std::abs(t0.norm() - 1) > 1e-9 || std::abs(t1.norm() - 1) > 1e-9) {
    return InvalidArgument("helix: tangents must be unit vectors");
  }
  const Eigen::Vector3d dt = t1 - t0;
  HelixElement h;
  h.start_mm = p0;
  h.start_tangent = t0;
  if (dt.norm() < 1e-12) {
    if (chord.normalized().dot(t0) < 1 - 1e-12) {
      return InvalidArgument(
          "helix: equal tangents but the chord is not along them (needs a full turn)");
    }
    h.length_mm = chord_len;
    return h;
  }
  if (std::abs(chord.dot(dt)) > 1e-9 * chord_len * dt.norm()) {
    return InvalidArgument("helix: the points and tangents are not co-helical (Eq. 3 residual " +
                           std::to_string(chord.dot(dt) / (chord_len * dt.norm())) + ")");
  }
  // The axis lies in the plane normal to t1 - t0: axis(phi) = cos(phi) e1 + sin(phi) e2.
  const Eigen::Vector3d n = dt.normalized();
  Eigen::Vector3d e1 = t0 + t1;
  if (e1.norm() < 1e-9) e1 = n.unitOrthogonal();
  e1 = (e1 - e1.dot(n) * n).normalized();
  const Eigen::Vector3d e2 = n.cross(e1);
  auto axis_at = [&](double phi) {
    return Eigen::Vector3d(std::cos(phi) * e1 + std::sin(phi) * e2);
  };
  // g(phi) must be parallel to the chord: both lie in the plane normal to n.
  int turns = 0;
  auto parallel_residual = [&](double phi, AxisCandidate* out) {
    *out = EvaluateAxis(axis_at(phi), t0, t1, turns);
    if (!out->valid) return std::numeric_limits<double>::quiet_NaN();
    return n.dot(out->scaled_chord.cross(chord)) / chord_len;
  };
  // Helices of more whole turns join the same ends: try them while their
  // length can still be closer to the preferred one.
  constexpr int kSamples = 720;
  constexpr int kMaxTurns = 64;
  double best_score = std::numeric_limits<double>::infinity();
  bool found = false;
  for (turns = 0; turns <= kMaxTurns; ++turns) {
    double shortest_this_turn = std::numeric_limits<double>::infinity();
    AxisCandidate a, b, mid;
    double phi_a = 0, f_a = parallel_residual(phi_a, &a);
    for (int i = 1; i <= kSamples; ++i) {
      const double phi_b = kTwoPi * i / kSamples;
      const double f_b = parallel_residual(phi_b, &b);
      if (std::isfinite(f_a) && std::isfinite(f_b) && (f_a == 0 || f_a * f_b < 0)) {
        double lo = phi_a, hi = phi_b, f_lo = f_a;
        for (int it = 0; it < 100 && hi - lo > 1e-16; ++it) {
          const double m = 0.5 * (lo + hi);
          const double f_m = parallel_residual(m, &mid);
          if (!std::isfinite(f_m)) break;
          if ((f_m < 0) == (f_lo < 0)) {
            lo = m;
            f_lo = f_m;
          } else {
            hi = m;
          }
        }
        AxisCandidate root;
        parallel_residual(0.5 * (lo + hi), &root);
        if (root.valid && root.scaled_chord.dot(chord) > 0) {
          HelixElement candidate = h;
          const double w = root.scaled_chord.norm() / chord_len;
          candidate.darboux_per_mm = w * root.axis;
          candidate.length_mm = root.theta / w;
          // A sign change across a jump of theta is no root: check the end.
          const bool reaches =
              (candidate.PointAt(candidate.length_mm) - p1).norm() < 1e-7 * chord_len &&
              (candidate.TangentAt(candidate.length_mm) - t1).norm() < 1e-7;
          const double score = preferred_length_mm > 0
                                   ? std::abs(candidate.length_mm - preferred_length_mm)
                                   : candidate.length_mm;
          if (reaches) shortest_this_turn = std::min(shortest_this_turn, candidate.length_mm);
          if (reaches && score < best_score) {
            best_score = score;
            h = candidate;
            found = true;
          }
        }
      }
      phi_a = phi_b;
      f_a = f_b;
    }
    // More turns only make longer helices.
    if (found && !(preferred_length_mm > 0 && shortest_this_turn < preferred_length_mm)) break;
  }
  if (!found) return InvalidArgument("helix: no helix joins the two points with these tangents");
  return h;
}

}  // namespace hairrig
