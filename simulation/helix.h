// One element of a piecewise-helical strand (Bao & Qi 2017, Sec. V-C): a helix
// given by its start point, its unit tangent there, its Darboux vector and its
// length. Millimetres; the Darboux vector is in radians per millimetre.
//
//   r(s) = p0 + tau_bar s Omega_bar + sin(w s)/w (t0 - tau_bar Omega_bar)
//             - (1 - cos(w s))/w (t0 x Omega_bar)                        (Eq. 8)
//   t(s) = t0 rotated about Omega_bar by w s
//
// with w = |Omega|, Omega_bar = Omega / w, tau_bar = <t0, Omega_bar>; the
// curvature is k = sqrt(w^2 - tau^2) and the torsion tau = w tau_bar (Eq. 6-7).
// w = 0 is a straight element.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"

namespace hairrig {

// Unit tangents closer than this are equal: the element between them is straight.
constexpr double kStraightTangentGap = 1e-9;

// [v]x: the matrix of the cross product, CrossMatrix(v) * w = v x w.
inline Eigen::Matrix3d CrossMatrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

struct HelixElement {
  Eigen::Vector3d start_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_tangent = Eigen::Vector3d::UnitZ();  // unit
  Eigen::Vector3d darboux_per_mm = Eigen::Vector3d::Zero();  // Omega
  double length_mm = 0;

  Eigen::Vector3d PointAt(double s_mm) const;
  Eigen::Vector3d TangentAt(double s_mm) const;
  // Both at once (one sine and cosine).
  void PointAndTangentAt(double s_mm, Eigen::Vector3d* point_mm, Eigen::Vector3d* tangent) const;
  // Appends the points at s = length k / count, k = 1..count (the start
  // point is not included), by a rotation recurrence: one sine and cosine in
  // all, accurate to about 1e-15 relative per step.
  void AppendSamples(int count, std::vector<Eigen::Vector3d>* out) const;
  double curvature_per_mm() const;
  double torsion_per_mm() const;
};

// r(s) - p0 of Eq. 8 for a unit start tangent t0 and Darboux vector omega:
// any length unit, omega in radians per that unit (the dynamics use metres).
Eigen::Vector3d HelixOffset(const Eigen::Vector3d& t0, const Eigen::Vector3d& omega, double s);

// Builds the element from curvature, torsion and length at a start point with
// a start tangent and principal normal (unit, orthogonal to the tangent).
HelixElement HelixFromCurvatureTorsion(const Eigen::Vector3d& start_mm,
                                       const Eigen::Vector3d& tangent,
                                       const Eigen::Vector3d& normal, double curvature_per_mm,
                                       double torsion_per_mm, double length_mm);

// Whether a helix turning t0 into t1 by less than pi, without extra turns
// (the short rotation), joins two points `chord` apart, the pair being
// co-helical: the chord must lean from t0 + t1 towards the binormal
// (t1 - t0) x (t0 + t1) by an angle psi with |tan psi| < 2c / (pi M),
// c = |t1 - t0| / 2, M = |t0 + t1| / 2 (f of HelixThrough's search then
// changes sign on the short branch). Unit tangents, any length unit.
bool ShortRotationExists(const Eigen::Vector3d& chord, const Eigen::Vector3d& t0,
                         const Eigen::Vector3d& t1);

// The helices through (p0, t0) and (p1, t1) that turn t0 into t1 with no
// extra turn: by less than pi (the short rotation) or by pi to 2 pi (the long
// one), found by Newton's method on quarters of the axis angle, without a
// scan; HelixThrough takes one of them when its length is within 2 % of the
// preferred one. At most one per quarter; empty when the pair is not
// co-helical, the tangents are equal or none checks out.
std::vector<HelixElement> HelicesWithoutExtraTurn(const Eigen::Vector3d& p0,
                                                  const Eigen::Vector3d& t0,
                                                  const Eigen::Vector3d& p1,
                                                  const Eigen::Vector3d& t1);

// The helix through p0 with tangent t0 that reaches p1 with tangent t1
// (interpolation of two points and two tangents, Sec. V-C after ref. [38]).
// The pair must be co-helical (Eq. 3, <p1 - p0, t1 - t0> = 0, relative to
// |p1 - p0|); of the helices that fit, the one whose length is closest to
// `preferred_length_mm` is returned (the shortest when it is 0). Equal
// tangents give a straight element when the chord is along them.
// InvalidArgument names the violated condition (coincident points, tangents
// not unit, not co-helical, no helix found).
// `axis_angle_rad`, if given, carries the helix axis's angle (radians, in the
// pair's own frame: e1 along t0 + t1, e2 = (t1 - t0) x e1 normalised) from
// one call to the next: in, where Newton's method starts for the short
// rotation of a turn over 29 deg and for the long rotation (neighbouring
// elements of a curl have nearly the same angle; a value outside their
// ranges is ignored); out, the returned helix's (NaN for a straight one).
Result<HelixElement> HelixThrough(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0,
                                  const Eigen::Vector3d& p1, const Eigen::Vector3d& t1,
                                  double preferred_length_mm = 0, double* axis_angle_rad = nullptr);

}  // namespace hairrig
