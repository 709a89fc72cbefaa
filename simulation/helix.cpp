#include "simulation/helix.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <vector>

namespace hairrig {

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
constexpr int kCoarseScan = 48;  // samples of the axis angle on [0, 2 pi]
constexpr int kFineScan = 720;
static_assert(kCoarseScan % 4 == 0 && kFineScan % 4 == 0, "ScanAngles folds |sin| by quarters");
constexpr int kMaxTurns = 64;
// Helices of more whole turns join the same ends; each extra turn costs this
// fraction of the preferred length when they compete (see HelixSearch::Run).
constexpr double kTurnPenalty = 0.02;
// A helix with no extra turn (the short or the long rotation) is taken when
// its length is within this fraction of the preferred one: one turn's
// penalty, so no helix of more turns could score better. (Looser tolerances
// let it replace exact multi-turn helices.)
constexpr double kZeroTurnTolerance = kTurnPenalty;
}

Eigen::Vector3d HelixOffset(const Eigen::Vector3d& t0, const Eigen::Vector3d& omega, double s) {
  const double w = omega.norm();
  if (w < 1e-15) return s * t0;
  const Eigen::Vector3d axis = omega / w;
  const double tau_bar = t0.dot(axis);
  return tau_bar * s * axis + std::sin(w * s) / w * (t0 - tau_bar * axis) - (1 - std::cos(w * s)) / w * t0.cross(axis);
}

Eigen::Vector3d HelixElement::PointAt(double s) const {
  return start_mm + HelixOffset(start_tangent, darboux_per_mm, s);
}

void HelixElement::AppendSamples(int count, std::vector<Eigen::Vector3d>* out) const {
  const double h = length_mm / count;
  const double w = darboux_per_mm.norm();
  if (w < 1e-15) {
    for (int k = 1; k <= count; ++k) out->push_back(start_mm + (h * k) * start_tangent);
    return;
  }
  // Eq. 8 over one step from any point of the helix: the offset is linear in
  // the tangent there, and the tangent turns about the axis by w h.
  const Eigen::Vector3d axis = darboux_per_mm / w;
  const double sin_step = std::sin(w * h), cos_step = std::cos(w * h);
  const double tau_bar = start_tangent.dot(axis);  // constant along the helix
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(w * h, axis).toRotationMatrix();
  Eigen::Vector3d point = start_mm, tangent = start_tangent;
  for (int k = 1; k <= count; ++k) {
    point += tau_bar * h * axis + sin_step / w * (tangent - tau_bar * axis) -
             (1 - cos_step) / w * tangent.cross(axis);
    tangent = turn * tangent;
    out->push_back(point);
  }
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

// The helices through (p0, t0) and (p1, t1), reduced to one scalar equation.
// In the plane P normal to n = (t1 - t0) / |t1 - t0| (it holds the axis, the
// chord and m = (t0 + t1) / 2), take e1 along m (M = |m|), e2 = n x e1, and
// the axis at angle phi: a = cos(phi) e1 + sin(phi) e2, a_perp = sin(phi) e1 -
// cos(phi) e2. With t0 = m - c n, t1 = m + c n (c = |t1 - t0| / 2):
//   tau_bar = M cos(phi);
//   the rotation about a taking t0 to t1 turns by theta = 2 atan(c / (M |sin phi|))
//   when sin(phi) < 0, else by 2 pi minus that (plus 2 pi per extra turn);
//   Eq. 8 at s = L gives the chord scaled by w: g = M theta cos(phi) a - 2 c a_perp.
// g must be parallel to the chord d = |d| (cos psi e1 + sin psi e2):
//   f(phi) = M theta cos(phi) sin(psi - phi) - 2 c cos(psi - phi) = 0, g.d > 0,
// and then w = |g| / |d|, L = theta / w. f is continuous in phi; its roots are
// bracketed on a scan and refined by bisection.
class HelixSearch {
 public:
  HelixSearch(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0, const Eigen::Vector3d& p1,
              const Eigen::Vector3d& t1)
      : p0_(p0), t0_(t0), p1_(p1), t1_(t1) {
    const Eigen::Vector3d n = (t1 - t0).normalized();
    const Eigen::Vector3d m = 0.5 * (t0 + t1);
    c_ = 0.5 * (t1 - t0).norm();
    m_ = m.norm();
    e1_ = m_ > 1e-12 ? Eigen::Vector3d(m / m_) : n.unitOrthogonal();
    e2_ = n.cross(e1_);
    const Eigen::Vector3d d = p1 - p0;
    chord_len_ = d.norm();
    psi_ = std::atan2(d.dot(e2_), d.dot(e1_));
    sin_psi_ = std::sin(psi_);
    cos_psi_ = std::cos(psi_);
  }

  // Helices of more whole turns join the same ends (a tight coil along the
  // chord can match almost any length). Each extra turn costs kTurnPenalty of
  // the preferred length in the score, so the search stops as soon as no
  // helix of more turns can beat the best one so far.
  bool Run(int samples, double preferred_length_mm, HelixElement* best) const {
    // The scan's angles, their sines and cosines and theta without extra
    // turns, computed once for all turns: one atan2 per distinct |sin phi|.
    const ScanAngles& angles = ScanAngles::For(samples);
    const std::vector<double>& phi = angles.phi;
    const size_t count = phi.size();
    // F is affine in theta: F = slope * theta - offset at each scanned angle.
    thread_local std::vector<double> slope, theta0, offset;
    slope.resize(count);
    theta0.resize(count);
    offset.resize(count);
    thread_local std::vector<double> half_turn;  // atan2(c, M |sin phi|) per distinct |sin phi|
    half_turn.resize(angles.abs_sin.size());
    for (size_t j = 0; j < half_turn.size(); ++j) half_turn[j] = std::atan2(c_, m_ * angles.abs_sin[j]);
    for (size_t k = 0; k < count; ++k) {
      const double sin_phi = angles.sin_phi[k], cos_phi = angles.cos_phi[k];
      const double half = half_turn[angles.abs_sin_index[k]];
      theta0[k] = sin_phi < 0 ? 2 * half : kTwoPi - 2 * half;  // ThetaFromSin(sin_phi, 0)
      offset[k] = -FromSinCos(sin_phi, cos_phi, 0);
      slope[k] = FromSinCos(sin_phi, cos_phi, 1) + offset[k];
    }
    double best_score = std::numeric_limits<double>::infinity();
    bool found = false;
    for (int turns = 0; turns <= kMaxTurns; ++turns) {
      const double turn_cost = kTurnPenalty * turns * preferred_length_mm;
      if (found && (preferred_length_mm <= 0 || turn_cost >= best_score)) break;
      auto f_at = [&](size_t k) { return slope[k] * (theta0[k] + kTwoPi * turns) - offset[k]; };
      double f_a = f_at(0);
      for (int i = 1; i <= samples; ++i) {
        const double f_b = f_at(static_cast<size_t>(i));
        HelixElement candidate;
        const bool bracket = f_a == 0 || f_a * f_b < 0;
        if (bracket && CanBeat(angles, theta0, static_cast<size_t>(i), turns, preferred_length_mm, best_score - turn_cost) &&
            Refine(phi[static_cast<size_t>(i) - 1], phi[static_cast<size_t>(i)], f_a, turns, &candidate)) {
          const double score = preferred_length_mm > 0
                                   ? std::abs(candidate.length_mm - preferred_length_mm) + turn_cost
                                   : candidate.length_mm;
          if (score < best_score && EndsAtTarget(candidate)) {
            best_score = score;
            *best = candidate;
            found = true;
          }
        }
        f_a = f_b;
      }
    }
    return found;
  }

  // The helices with no extra turn, found without the scan. The short
  // rotation has sin(phi) < 0 (phi in (pi, 2 pi)): t0 turns to t1 by less
  // than pi. f at pi, 3 pi / 2 and 2 pi brackets it; Newton starts from the
  // small-angle expansion of f,
  //   f ~ (2c / |sin phi|) (sin psi - c^2 cos(phi) sin(psi - phi) / (3 M^2 sin^2 phi)),
  // whose root for small psi is cot(phi) = -3 M^2 sin(psi) / c^2 (a planar
  // arc, psi = 0, has its axis at 3 pi / 2, along t0 x t1). The long
  // rotation has sin(phi) > 0 (phi in (0, pi)): t0 turns to t1 by between
  // pi and 2 pi (an element over about half a curl or more); f at 0, pi / 2
  // and pi bracket it, Newton starts mid-bracket. False when f does not
  // change sign on the half (for the short rotation: the chord leans too far
  // from t0 + t1) or no helix checks out.
  bool ShortRotation(double preferred_length_mm, HelixElement* out) const {
    const double guess = kTwoPi + std::atan2(-1.0, 3 * m_ * m_ * sin_psi_ / (c_ * c_));
    return ZeroTurnRoot(-1, guess, preferred_length_mm, out);
  }
  bool LongRotation(double preferred_length_mm, HelixElement* out) const {
    return ZeroTurnRoot(1, -1, preferred_length_mm, out);
  }

 private:
  // The root on the half of the axis angles where sin(phi) has the sign
  // `side`: (sin, cos) = (0, side), (side, 0), (0, -side) at its start,
  // middle and end bracket a root in each quarter where f changes sign (f
  // often has one in each, of which one has g against the chord). Of the
  // helices found, the one of length closest to `preferred_length_mm`.
  // Newton starts from `guess` if it is inside the quarter.
  bool ZeroTurnRoot(double side, double guess, double preferred_length_mm, HelixElement* out) const {
    constexpr double kPi = kTwoPi / 2;
    const double first = side < 0 ? kPi : 0;
    const double f[3] = {FromSinCos(0, side, kPi), FromSinCos(side, 0, ThetaFromSin(side, 0)),
                         FromSinCos(0, -side, kPi)};
    bool found = false;
    for (int quarter = 0; quarter < 2; ++quarter) {
      if ((f[quarter] < 0) == (f[quarter + 1] < 0)) continue;
      const double lo = first + quarter * kPi / 2, hi = lo + kPi / 2;
      const double start = guess > lo && guess < hi ? guess : 0.5 * (lo + hi);
      HelixElement candidate;
      if (!RefineFrom(start, lo, hi, f[quarter], 0, &candidate) || !EndsAtTarget(candidate)) continue;
      if (!found || std::abs(candidate.length_mm - preferred_length_mm) < std::abs(out->length_mm - preferred_length_mm)) {
        *out = candidate;
        found = true;
      }
    }
    return found;
  }

  struct ScanAngles;
  // Whether a root between samples k - 1 and k can score below `budget`: the
  // helix length L = theta |d| / |g| at the two ends bounds it (L varies
  // slowly and monotonically across a bracket of the coarse scan).
  bool CanBeat(const ScanAngles& angles, const std::vector<double>& theta0, size_t k, int turns,
               double preferred_length_mm, double budget) const {
    if (preferred_length_mm <= 0 || !std::isfinite(budget)) return true;
    auto length = [&](size_t j) {
      const double theta = theta0[j] + kTwoPi * turns;
      return theta * chord_len_ / std::hypot(m_ * theta * angles.cos_phi[j], 2 * c_);
    };
    const double lo = std::min(length(k - 1), length(k)), hi = std::max(length(k - 1), length(k));
    const double miss = preferred_length_mm < lo ? lo - preferred_length_mm
                        : preferred_length_mm > hi ? preferred_length_mm - hi
                                                   : 0.0;
    return miss < budget * 1.5 + 1e-9 * preferred_length_mm;
  }
  // The scan's angles with their sines and cosines, for the two scan densities.
  // |sin phi| takes samples / 4 + 1 distinct values on the grid (samples is a
  // multiple of 4): abs_sin holds them, abs_sin_index maps each angle to its.
  struct ScanAngles {
    std::vector<double> phi, sin_phi, cos_phi, abs_sin;
    std::vector<size_t> abs_sin_index;
    static const ScanAngles& For(int samples) {
      static const ScanAngles coarse(kCoarseScan), fine(kFineScan);
      return samples == kCoarseScan ? coarse : fine;
    }
    explicit ScanAngles(int samples) {
      const int quarter = samples / 4;
      for (int j = 0; j <= quarter; ++j) abs_sin.push_back(std::sin(kTwoPi * j / samples));
      for (int i = 0; i <= samples; ++i) {
        phi.push_back(kTwoPi * i / samples);
        sin_phi.push_back(std::sin(phi.back()));
        cos_phi.push_back(std::cos(phi.back()));
        const int in_half = i % (2 * quarter);  // |sin| has period pi and is even about pi / 2
        abs_sin_index.push_back(static_cast<size_t>(std::min(in_half, 2 * quarter - in_half)));
      }
    }
  };
  double ThetaFromSin(double sin_phi, int turns) const {
    const double half = std::atan2(c_, m_ * std::abs(sin_phi));
    return (sin_phi < 0 ? 2 * half : kTwoPi - 2 * half) + kTwoPi * turns;
  }
  double Theta(double phi, int turns) const { return ThetaFromSin(std::sin(phi), turns); }
  // f from the sine and cosine of phi; those of psi - phi follow from psi's.
  double FromSinCos(double sin_phi, double cos_phi, double theta) const {
    const double sin_rel = sin_psi_ * cos_phi - cos_psi_ * sin_phi;  // sin(psi - phi)
    const double cos_rel = cos_psi_ * cos_phi + sin_psi_ * sin_phi;
    return m_ * theta * cos_phi * sin_rel - 2 * c_ * cos_rel;
  }

  // The root on [lo, hi]; true with the helix if g points along the chord.
  // Newton's method on f with its analytic
  // derivative, kept inside the bracket (a bisection step whenever Newton
  // would leave it): quadratic near a simple root, never lost.
  bool Refine(double lo, double hi, double f_lo, int turns, HelixElement* out) const {
    return RefineFrom(0.5 * (lo + hi), lo, hi, f_lo, turns, out);
  }
  bool RefineFrom(double phi, double lo, double hi, double f_lo, int turns, HelixElement* out) const {
    if (f_lo == 0) return Build(lo, turns, out);
    const bool rising = f_lo < 0;  // f(lo) < 0 < f(hi)
    for (int it = 0; it < 100; ++it) {
      double f, df;
      FAndDerivative(phi, turns, &f, &df);
      if (std::abs(f) < 1e-15) break;
      if ((f < 0) == rising) {
        lo = phi;
      } else {
        hi = phi;
      }
      double next = phi - f / df;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const double step = std::abs(next - phi);
      phi = next;
      if (step < 1e-12 || hi - lo < 1e-15) break;
    }
    return Build(phi, turns, out);
  }

  // f and df/dphi, with theta' = 2 c M cos(phi) / (M^2 sin^2(phi) + c^2) on
  // both branches and d/dphi [cos(phi) sin(psi - phi)] = -cos(psi - 2 phi).
  void FAndDerivative(double phi, int turns, double* f, double* df) const {
    const double sin_phi = std::sin(phi), cos_phi = std::cos(phi);
    const double theta = ThetaFromSin(sin_phi, turns);
    const double sin_rel = sin_psi_ * cos_phi - cos_psi_ * sin_phi;  // sin(psi - phi)
    const double cos_rel = cos_psi_ * cos_phi + sin_psi_ * sin_phi;
    const double cos_psi_2phi = cos_rel * cos_phi + sin_rel * sin_phi;
    const double dtheta = 2 * c_ * m_ * cos_phi / (m_ * m_ * sin_phi * sin_phi + c_ * c_);
    *f = m_ * theta * cos_phi * sin_rel - 2 * c_ * cos_rel;
    *df = m_ * dtheta * cos_phi * sin_rel - m_ * theta * cos_psi_2phi - 2 * c_ * sin_rel;
  }

  // The helix of axis angle phi (a root of f); false if g points against the
  // chord. Whether it really ends at (p1, t1) is EndsAtTarget's check.
  bool Build(double phi, int turns, HelixElement* out) const {
    const double theta = Theta(phi, turns);
    const double axial = m_ * theta * std::cos(phi);
    if (axial * std::cos(psi_ - phi) + 2 * c_ * std::sin(psi_ - phi) <= 0)
      return false;  // g against the chord
    const double w = std::hypot(axial, 2 * c_) / chord_len_;
    out->start_mm = p0_;
    out->start_tangent = t0_;
    out->darboux_per_mm = w * (std::cos(phi) * e1_ + std::sin(phi) * e2_);
    out->length_mm = theta / w;
    return true;
  }
  bool EndsAtTarget(const HelixElement& h) const {
    return (h.PointAt(h.length_mm) - p1_).norm() < 1e-7 * chord_len_ &&
           (h.TangentAt(h.length_mm) - t1_).norm() < 1e-7;
  }

  Eigen::Vector3d p0_, t0_, p1_, t1_;
  Eigen::Vector3d e1_, e2_;
  double c_ = 0, m_ = 0, psi_ = 0, chord_len_ = 0;
  double sin_psi_ = 0, cos_psi_ = 1;
};

}  // namespace

bool ShortRotationExists(const Eigen::Vector3d& chord, const Eigen::Vector3d& t0,
                         const Eigen::Vector3d& t1) {
  const Eigen::Vector3d sum = t0 + t1, gap = t1 - t0;
  const double m = 0.5 * sum.norm(), c = 0.5 * gap.norm();
  if (!(m > 1e-12) || !(c > 0)) return false;
  const Eigen::Vector3d e1 = sum / (2 * m);
  const Eigen::Vector3d e2 = (gap / (2 * c)).cross(e1);
  const double along = chord.dot(e1), across = chord.dot(e2);
  return along > 0 && std::abs(across) * kTwoPi * m < 4 * c * along;
}

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
  // The usual cases in fitting, a short element of a smooth strand or half a
  // curl: the short or the long rotation, when its length is close to the
  // preferred one; otherwise the scan (the fine one only when the coarse one
  // misses a root).
  auto close_to_preferred = [&](const HelixElement& e) {
    return std::abs(e.length_mm - preferred_length_mm) < kZeroTurnTolerance * preferred_length_mm;
  };
  if (preferred_length_mm > 0 && ((search.ShortRotation(preferred_length_mm, &h) && close_to_preferred(h)) ||
                                  (search.LongRotation(preferred_length_mm, &h) && close_to_preferred(h)))) {
    return h;
  }
  bool found = false;
  for (int samples : {kCoarseScan, kFineScan}) {
    found = search.Run(samples, preferred_length_mm, &h);
    if (found) break;
  }
  if (!found) return InvalidArgument("helix: no helix joins the two points with these tangents");
  return h;
}

}  // namespace hairrig
