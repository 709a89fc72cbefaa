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

// The helices through (p0, t0) and (p1, t1): their axis lies in the plane
// normal to t1 - t0, axis(phi) = cos(phi) e1 + sin(phi) e2, and must make the
// scaled chord g parallel to p1 - p0 (both lie in that plane, so this is one
// scalar equation in phi). Roots are bracketed on a scan of phi, refined by
// bisection and kept only if the helix really ends at (p1, t1).
class HelixSearch {
 public:
  HelixSearch(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0, const Eigen::Vector3d& p1,
              const Eigen::Vector3d& t1)
      : p0_(p0), t0_(t0), p1_(p1), t1_(t1), chord_(p1 - p0), chord_len_(chord_.norm()) {
    n_ = (t1 - t0).normalized();
    Eigen::Vector3d e1 = t0 + t1;
    if (e1.norm() < 1e-9) e1 = n_.unitOrthogonal();
    e1_ = (e1 - e1.dot(n_) * n_).normalized();
    e2_ = n_.cross(e1_);
  }

  // Helices of more whole turns join the same ends: they are tried while their
  // length can still come closer to the preferred one.
  bool Run(int samples, double preferred_length_mm, HelixElement* best) {
    constexpr int kMaxTurns = 64;
    double best_score = std::numeric_limits<double>::infinity();
    bool found = false;
    for (int turns = 0; turns <= kMaxTurns; ++turns) {
      double shortest = std::numeric_limits<double>::infinity();
      double phi_a = 0, f_a = Residual(phi_a, turns, nullptr);
      for (int i = 1; i <= samples; ++i) {
        const double phi_b = kTwoPi * i / samples;
        const double f_b = Residual(phi_b, turns, nullptr);
        HelixElement candidate;
        if (std::isfinite(f_a) && std::isfinite(f_b) && (f_a == 0 || f_a * f_b < 0) &&
            Refine(phi_a, phi_b, f_a, turns, &candidate)) {
          shortest = std::min(shortest, candidate.length_mm);
          const double score = preferred_length_mm > 0
                                   ? std::abs(candidate.length_mm - preferred_length_mm)
                                   : candidate.length_mm;
          if (score < best_score) {
            best_score = score;
            *best = candidate;
            found = true;
          }
        }
        phi_a = phi_b;
        f_a = f_b;
      }
      if (found && !(preferred_length_mm > 0 && shortest < preferred_length_mm)) break;
    }
    return found;
  }

 private:
  double Residual(double phi, int turns, AxisCandidate* out) const {
    const AxisCandidate c =
        EvaluateAxis(std::cos(phi) * e1_ + std::sin(phi) * e2_, t0_, t1_, turns);
    if (out) *out = c;
    if (!c.valid) return std::numeric_limits<double>::quiet_NaN();
    return n_.dot(c.scaled_chord.cross(chord_)) / chord_len_;
  }

  // Bisection on [lo, hi]; true with the helix if the root is a real one (a
  // sign change across a jump of theta is not).
  bool Refine(double lo, double hi, double f_lo, int turns, HelixElement* out) const {
    for (int it = 0; it < 100 && hi - lo > 1e-16; ++it) {
      const double m = 0.5 * (lo + hi);
      const double f_m = Residual(m, turns, nullptr);
      if (!std::isfinite(f_m)) return false;
      if ((f_m < 0) == (f_lo < 0)) {
        lo = m;
        f_lo = f_m;
      } else {
        hi = m;
      }
    }
    AxisCandidate root;
    Residual(0.5 * (lo + hi), turns, &root);
    if (!root.valid || root.scaled_chord.dot(chord_) <= 0) return false;
    const double w = root.scaled_chord.norm() / chord_len_;
    out->start_mm = p0_;
    out->start_tangent = t0_;
    out->darboux_per_mm = w * root.axis;
    out->length_mm = root.theta / w;
    return (out->PointAt(out->length_mm) - p1_).norm() < 1e-7 * chord_len_ &&
           (out->TangentAt(out->length_mm) - t1_).norm() < 1e-7;
  }

  Eigen::Vector3d p0_, t0_, p1_, t1_, chord_;
  double chord_len_;
  Eigen::Vector3d n_, e1_, e2_;
};

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
  if (dt.norm() < kStraightTangentGap) {
    if (chord.normalized().dot(t0) < 1 - kStraightTangentGap) {
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
  HelixSearch search(p0, t0, p1, t1);
  bool found = false;
  for (int samples : {90, 720}) {  // a finer scan only when the coarse one misses a root
    found = search.Run(samples, preferred_length_mm, &h);
    if (found) break;
  }
  if (!found) return InvalidArgument("helix: no helix joins the two points with these tangents");
  return h;
}

}  // namespace hairrig
