#include "simulation/helix.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/transform.h"

namespace hairrig {

namespace {
constexpr double kTwoPi = 2 * kPi;
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

// Eq. 8's offset over arc length s from a point with unit tangent t, for the
// unit axis, tau_bar = <t, axis>, w = |Omega| and the sine and cosine of w s.
Eigen::Vector3d OffsetAlong(const Eigen::Vector3d& t, const Eigen::Vector3d& axis, double tau_bar,
                            double w, double s, double sin_ws, double cos_ws) {
  return tau_bar * s * axis + sin_ws / w * (t - tau_bar * axis) - (1 - cos_ws) / w * t.cross(axis);
}
}  // namespace

Eigen::Vector3d HelixOffset(const Eigen::Vector3d& t0, const Eigen::Vector3d& omega, double s) {
  const double w = omega.norm();
  if (w < 1e-15) return s * t0;
  const Eigen::Vector3d axis = omega / w;
  return OffsetAlong(t0, axis, t0.dot(axis), w, s, std::sin(w * s), std::cos(w * s));
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
    point += OffsetAlong(tangent, axis, tau_bar, w, h, sin_step, cos_step);
    tangent = turn * tangent;
    out->push_back(point);
  }
}

Eigen::Vector3d HelixElement::TangentAt(double s) const {
  Eigen::Vector3d point, tangent;
  PointAndTangentAt(s, &point, &tangent);
  return tangent;
}

// Eq. 8 and its derivative with one sine and cosine.
void HelixElement::PointAndTangentAt(double s, Eigen::Vector3d* point,
                                     Eigen::Vector3d* tangent) const {
  const double w = darboux_per_mm.norm();
  if (w < 1e-15) {
    *point = start_mm + s * start_tangent;
    *tangent = start_tangent;
    return;
  }
  const Eigen::Vector3d axis = darboux_per_mm / w;
  const double tau_bar = start_tangent.dot(axis);
  const double sin_ws = std::sin(w * s), cos_ws = std::cos(w * s);
  *point = start_mm + OffsetAlong(start_tangent, axis, tau_bar, w, s, sin_ws, cos_ws);
  *tangent = start_tangent + (cos_ws - 1) * (start_tangent - tau_bar * axis) -
             sin_ws * start_tangent.cross(axis);
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

// A helix found by the search, at axis angle phi.
struct Root {
  double phi = 0;
  HelixElement helix;
};
// The roots the short and the long rotation found (at most one per quarter
// of the axis angle, four in all).
struct ZeroTurnRoots {
  Root root[4];
  int count = 0;
  // The one whose length is closest to `preferred_length_mm`; null if none.
  const Root* Closest(double preferred_length_mm) const {
    const Root* best = nullptr;
    for (int i = 0; i < count; ++i) {
      if (!best || std::abs(root[i].helix.length_mm - preferred_length_mm) <
                       std::abs(best->helix.length_mm - preferred_length_mm))
        best = &root[i];
    }
    return best;
  }
  bool Within(double lo, double hi) const {
    for (int i = 0; i < count; ++i)
      if (root[i].phi >= lo && root[i].phi <= hi) return true;
    return false;
  }
};

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
// bracketed (on quarters of phi or on a scan) and refined by bracketed Newton.
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
    // The chord lies in P (the pair is co-helical): its angle psi from e1.
    const double along = d.dot(e1_), across = d.dot(e2_);
    const double in_plane = std::sqrt(along * along + across * across);
    if (in_plane > 0) {
      cos_psi_ = along / in_plane;
      sin_psi_ = across / in_plane;
    }
  }

  // Helices of more whole turns join the same ends (a tight coil along the
  // chord can match almost any length). Each extra turn costs kTurnPenalty of
  // the preferred length in the score, so the search stops as soon as no
  // helix of more turns can beat the best one so far. The `known` roots
  // start the search as the best so far, and the scan does not refine their
  // brackets again.
  bool Run(int samples, double preferred_length_mm, const ZeroTurnRoots& known, Root* best) const {
    // The scan's angles, their sines and cosines and theta without extra
    // turns, computed once for all turns: one atan2 per distinct |sin phi|.
    const ScanAngles& angles = ScanAngles::For(samples);
    const std::vector<double>& phi = angles.phi;
    const size_t count = phi.size();
    // f is affine in theta, f = M cos(phi) sin(psi - phi) theta - 2 c cos(psi
    // - phi), and so in the turns T: f = base + T step at each scanned angle.
    thread_local std::vector<double> theta0, base, step;
    theta0.resize(count);
    base.resize(count);
    step.resize(count);
    thread_local std::vector<double> half_turn;  // atan2(c, M |sin phi|) per distinct |sin phi|
    half_turn.resize(angles.abs_sin.size());
    for (size_t j = 0; j < half_turn.size(); ++j)
      half_turn[j] = std::atan2(c_, m_ * angles.abs_sin[j]);
    for (size_t k = 0; k < count; ++k) {
      const double sin_phi = angles.sin_phi[k], cos_phi = angles.cos_phi[k];
      theta0[k] = ThetaFromHalf(sin_phi, half_turn[angles.abs_sin_index[k]], 0);
      const double slope = m_ * cos_phi * SinChordFromAxis(sin_phi, cos_phi);
      base[k] = slope * theta0[k] - 2 * c_ * CosChordFromAxis(sin_phi, cos_phi);
      step[k] = kTwoPi * slope;
    }
    double best_score = std::numeric_limits<double>::infinity();
    bool found = false;
    if (const Root* closest = known.Closest(preferred_length_mm);
        closest && preferred_length_mm > 0) {
      best_score = std::abs(closest->helix.length_mm - preferred_length_mm);
      *best = *closest;
      found = true;
    }
    for (int turns = 0; turns <= kMaxTurns; ++turns) {
      const double turn_cost = kTurnPenalty * turns * preferred_length_mm;
      if (found && (preferred_length_mm <= 0 || turn_cost >= best_score)) break;
      auto f_at = [&](size_t k) { return base[k] + turns * step[k]; };
      double f_a = f_at(0);
      for (int i = 1; i <= samples; ++i) {
        const double f_b = f_at(static_cast<size_t>(i));
        Root candidate;
        const bool bracket = (f_a == 0 || f_a * f_b < 0) &&
                             !(turns == 0 && known.Within(phi[static_cast<size_t>(i) - 1],
                                                          phi[static_cast<size_t>(i)]));
        if (bracket &&
            CanBeat(angles, theta0, static_cast<size_t>(i), turns, preferred_length_mm,
                    best_score - turn_cost) &&
            Refine(phi[static_cast<size_t>(i) - 1], phi[static_cast<size_t>(i)], f_a, f_b, turns,
                   &candidate)) {
          const double length = candidate.helix.length_mm;
          const double score =
              preferred_length_mm > 0 ? std::abs(length - preferred_length_mm) + turn_cost : length;
          if (score < best_score && EndsAtTarget(candidate.helix)) {
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
  // previous element's root (`hint`) if the turn is not small (c > 1/4),
  // else from the small-angle expansion of f,
  //   f ~ (2c / |sin phi|) (sin psi - c^2 cos(phi) sin(psi - phi) / (3 M^2 sin^2 phi)),
  // whose root for small psi is cot(phi) = -3 M^2 sin(psi) / c^2 (a planar
  // arc, psi = 0, has its axis at 3 pi / 2, along t0 x t1). The long
  // rotation has sin(phi) > 0 (phi in (0, pi)): t0 turns to t1 by between
  // pi and 2 pi (an element over about half a curl or more); f at 0, pi / 2
  // and pi bracket it, Newton starts from the hint or mid-bracket. Each adds
  // the helices that check out to `roots` (at most two): none when f does
  // not change sign on the half (for the short rotation: the chord leans too
  // far from t0 + t1).
  void ShortRotation(double hint, ZeroTurnRoots* roots) const {
    constexpr double kSmallTurn = 0.25;  // c, the sine of half the turn: 29 deg
    const bool hint_on_half = hint > kTwoPi / 2 && hint < kTwoPi;
    const double guess = c_ > kSmallTurn && hint_on_half
                             ? hint
                             : kTwoPi + std::atan2(-1.0, 3 * m_ * m_ * sin_psi_ / (c_ * c_));
    ZeroTurnRoot(-1, guess, roots);
  }
  void LongRotation(double hint, ZeroTurnRoots* roots) const { ZeroTurnRoot(1, hint, roots); }

 private:
  // The root on the half of the axis angles where sin(phi) has the sign
  // `side`: (sin, cos) = (0, side), (side, 0), (0, -side) at its start,
  // middle and end bracket a root in each quarter where f changes sign (f
  // often has one in each, of which one has g against the chord). Newton
  // starts from `guess` if it is inside the quarter.
  void ZeroTurnRoot(double side, double guess, ZeroTurnRoots* roots) const {
    const double first = side < 0 ? kPi : 0;
    const double f[3] = {FromSinCos(0, side, kPi), FromSinCos(side, 0, ThetaFromSin(side, 0)),
                         FromSinCos(0, -side, kPi)};
    for (int quarter = 0; quarter < 2; ++quarter) {
      if ((f[quarter] < 0) == (f[quarter + 1] < 0)) continue;
      const double lo = first + quarter * kPi / 2, hi = lo + kPi / 2;
      Root& root = roots->root[roots->count];
      root.phi = guess > lo && guess < hi ? guess : 0.5 * (lo + hi);
      if (RefineFrom(root.phi, lo, hi, f[quarter], f[quarter + 1], 0, &root) &&
          EndsAtTarget(root.helix))
        ++roots->count;
    }
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
      return theta * chord_len_ / GNorm(m_ * theta * angles.cos_phi[j]);
    };
    const double lo = std::min(length(k - 1), length(k)), hi = std::max(length(k - 1), length(k));
    const double miss = preferred_length_mm < lo   ? lo - preferred_length_mm
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
  // theta from half = atan2(c, M |sin phi|): 2 half on the short branch, 2 pi
  // - 2 half on the long one, plus the extra turns.
  static double ThetaFromHalf(double sin_phi, double half, int turns) {
    return (sin_phi < 0 ? 2 * half : kTwoPi - 2 * half) + kTwoPi * turns;
  }
  double ThetaFromSin(double sin_phi, int turns) const {
    return ThetaFromHalf(sin_phi, std::atan2(c_, m_ * std::abs(sin_phi)), turns);
  }
  // |g| for g's component M theta cos(phi) along the axis (no overflow: it is
  // below 500, and 2c below 2).
  double GNorm(double axial) const { return std::sqrt(axial * axial + 4 * c_ * c_); }
  // The sine and cosine of psi - phi (the chord's angle from the axis).
  double SinChordFromAxis(double sin_phi, double cos_phi) const {
    return sin_psi_ * cos_phi - cos_psi_ * sin_phi;
  }
  double CosChordFromAxis(double sin_phi, double cos_phi) const {
    return cos_psi_ * cos_phi + sin_psi_ * sin_phi;
  }
  // f from the sine and cosine of phi.
  double FromSinCos(double sin_phi, double cos_phi, double theta) const {
    return m_ * theta * cos_phi * SinChordFromAxis(sin_phi, cos_phi) -
           2 * c_ * CosChordFromAxis(sin_phi, cos_phi);
  }

  // An axis angle with its sine and cosine, the turn theta about it (with
  // the search's extra turns) and dtheta / dphi, from theta' = 2 c M cos(phi)
  // / (M^2 sin^2(phi) + c^2) on both branches.
  struct Axis {
    double phi, sin, cos, theta, dtheta;
  };
  Axis AxisAt(double phi, int turns) const {
    Axis a{phi, std::sin(phi), std::cos(phi), 0, 0};
    a.theta = ThetaFromSin(a.sin, turns);
    a.dtheta = 2 * c_ * m_ * a.cos / (m_ * m_ * a.sin * a.sin + c_ * c_);
    return a;
  }
  // The axis moved by a step below 1e-12 rad, to first order. The neglected
  // theta'' step^2 / 2 (|theta''| up to about 2 (M / c)^2) is below 1e-16 rad
  // for turns over 0.01 deg (c > 1e-4); EndsAtTarget checks the helix in any case.
  static Axis MovedSlightly(const Axis& a, double step) {
    return {a.phi + step, a.sin + a.cos * step, a.cos - a.sin * step, a.theta + a.dtheta * step,
            a.dtheta};
  }

  // The root on [lo, hi]; true with the helix if g points along the chord.
  // Newton's method on f with its analytic derivative, kept inside the
  // bracket (a regula falsi step whenever Newton would leave it): quadratic
  // near a simple root, never lost.
  bool Refine(double lo, double hi, double f_lo, double f_hi, int turns, Root* out) const {
    return RefineFrom(0.5 * (lo + hi), lo, hi, f_lo, f_hi, turns, out);
  }
  // From phi.
  bool RefineFrom(double phi, double lo, double hi, double f_lo, double f_hi, int turns,
                  Root* out) const {
    constexpr double kTolerance = 1e-12;
    if (f_lo == 0) {
      out->phi = lo;
      return Build(AxisAt(lo, turns), &out->helix);
    }
    const bool rising = f_lo < 0;  // f(lo) < 0 < f(hi)
    Axis axis = AxisAt(phi, turns);
    for (int it = 0; it < 100; ++it) {
      double f, df;
      FAndDerivative(axis, &f, &df);
      if (std::abs(f) < 1e-15) break;
      if ((f < 0) == rising) {
        lo = phi;
        f_lo = f;
      } else {
        hi = phi;
        f_hi = f;
      }
      double next = phi - f / df;
      const bool newton = next > lo && next < hi;
      if (!newton) next = Secant(lo, hi, f_lo, f_hi);
      const double step = next - phi;
      phi = next;
      axis = newton && std::abs(step) < kTolerance ? MovedSlightly(axis, step) : AxisAt(phi, turns);
      if (std::abs(step) < kTolerance || hi - lo < 1e-15) break;
    }
    out->phi = axis.phi;
    return Build(axis, &out->helix);
  }

  // Where the chord between the bracket's ends crosses zero (regula falsi),
  // kept a tenth of the bracket from either end (bisection if the values
  // say nothing); Newton's fallback.
  static double Secant(double lo, double hi, double f_lo, double f_hi) {
    const double fraction = f_lo / (f_lo - f_hi);
    if (!(fraction > 0 && fraction < 1)) return 0.5 * (lo + hi);
    return lo + (hi - lo) * std::clamp(fraction, 0.1, 0.9);
  }

  // f and df/dphi, with d/dphi [cos(phi) sin(psi - phi)] = -cos(psi - 2 phi).
  void FAndDerivative(const Axis& a, double* f, double* df) const {
    const double sin_rel = SinChordFromAxis(a.sin, a.cos), cos_rel = CosChordFromAxis(a.sin, a.cos);
    const double cos_psi_2phi = cos_rel * a.cos + sin_rel * a.sin;
    *f = m_ * a.theta * a.cos * sin_rel - 2 * c_ * cos_rel;
    *df = m_ * a.dtheta * a.cos * sin_rel - m_ * a.theta * cos_psi_2phi - 2 * c_ * sin_rel;
  }

  // The helix of axis angle a (a root of f); false if g points against the
  // chord. Whether it really ends at (p1, t1) is EndsAtTarget's check.
  bool Build(const Axis& a, HelixElement* out) const {
    const double axial = m_ * a.theta * a.cos;
    const double sin_rel = SinChordFromAxis(a.sin, a.cos), cos_rel = CosChordFromAxis(a.sin, a.cos);
    if (axial * cos_rel + 2 * c_ * sin_rel <= 0) return false;  // g against the chord
    const double w = GNorm(axial) / chord_len_;
    out->start_mm = p0_;
    out->start_tangent = t0_;
    out->darboux_per_mm = w * (a.cos * e1_ + a.sin * e2_);
    out->length_mm = a.theta / w;
    return true;
  }
  bool EndsAtTarget(const HelixElement& h) const {
    Eigen::Vector3d end, tangent;
    h.PointAndTangentAt(h.length_mm, &end, &tangent);
    return (end - p1_).norm() < 1e-7 * chord_len_ && (tangent - t1_).norm() < 1e-7;
  }

  Eigen::Vector3d p0_, t0_, p1_, t1_;
  Eigen::Vector3d e1_, e2_;
  double c_ = 0, m_ = 0, chord_len_ = 0;
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

namespace {

// HelixThrough's conditions on its input (the co-helical one unless the
// tangents are equal).
Status CheckPair(const Eigen::Vector3d& chord, const Eigen::Vector3d& t0,
                 const Eigen::Vector3d& t1) {
  const double chord_len = chord.norm();
  if (!(chord_len > 1e-12) || !chord.allFinite())
    return InvalidArgument("helix: the two points coincide or are not finite");
  if (std::abs(t0.norm() - 1) > 1e-9 || std::abs(t1.norm() - 1) > 1e-9) {
    return InvalidArgument("helix: tangents must be unit vectors");
  }
  const Eigen::Vector3d dt = t1 - t0;
  if (dt.norm() >= kStraightTangentGap && std::abs(chord.dot(dt)) > 1e-9 * chord_len * dt.norm()) {
    return InvalidArgument("helix: the points and tangents are not co-helical (Eq. 3 residual " +
                           std::to_string(chord.dot(dt) / (chord_len * dt.norm())) + ")");
  }
  return Status::Ok();
}

}  // namespace

std::vector<HelixElement> HelicesWithoutExtraTurn(const Eigen::Vector3d& p0,
                                                  const Eigen::Vector3d& t0,
                                                  const Eigen::Vector3d& p1,
                                                  const Eigen::Vector3d& t1) {
  std::vector<HelixElement> helices;
  if (!CheckPair(p1 - p0, t0, t1).ok() || (t1 - t0).norm() < kStraightTangentGap) return helices;
  const HelixSearch search(p0, t0, p1, t1);
  ZeroTurnRoots roots;
  search.ShortRotation(-1, &roots);
  search.LongRotation(-1, &roots);
  for (int i = 0; i < roots.count; ++i) helices.push_back(roots.root[i].helix);
  return helices;
}

Result<HelixElement> HelixThrough(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0,
                                  const Eigen::Vector3d& p1, const Eigen::Vector3d& t1,
                                  double preferred_length_mm, double* axis_angle_rad) {
  const double hint = axis_angle_rad ? *axis_angle_rad : -1;
  if (axis_angle_rad) *axis_angle_rad = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d chord = p1 - p0;
  HR_RETURN_IF_ERROR(CheckPair(chord, t0, t1));
  if ((t1 - t0).norm() < kStraightTangentGap) {
    if (chord.normalized().dot(t0) < 1 - kStraightTangentGap) {
      return InvalidArgument(
          "helix: equal tangents but the chord is not along them (needs a full turn)");
    }
    HelixElement straight;
    straight.start_mm = p0;
    straight.start_tangent = t0;
    straight.length_mm = chord.norm();
    return straight;
  }
  HelixSearch search(p0, t0, p1, t1);
  // The usual cases in fitting, a short element of a smooth strand or half a
  // curl: the short or the long rotation, when its length is close to the
  // preferred one; otherwise the scan (the fine one only when the coarse one
  // misses a root).
  auto close_to_preferred = [&](const HelixElement& e) {
    return std::abs(e.length_mm - preferred_length_mm) < kZeroTurnTolerance * preferred_length_mm;
  };
  auto found = [&](const Root& root) {
    if (axis_angle_rad) *axis_angle_rad = root.phi;
    return root.helix;
  };
  ZeroTurnRoots known;
  if (preferred_length_mm > 0) {
    search.ShortRotation(hint, &known);
    if (const auto* root = known.Closest(preferred_length_mm);
        root && close_to_preferred(root->helix))
      return found(*root);
    search.LongRotation(hint, &known);
    if (const auto* root = known.Closest(preferred_length_mm);
        root && close_to_preferred(root->helix))
      return found(*root);
  }
  Root best;
  for (int samples : {kCoarseScan, kFineScan}) {
    if (search.Run(samples, preferred_length_mm, known, &best)) return found(best);
  }
  return InvalidArgument("helix: no helix joins the two points with these tangents");
}

}  // namespace hairrig
