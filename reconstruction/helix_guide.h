// A strand grown along a helix of known radius and pitch whose axis follows
// a direction field: the curl a ringlet keeps where no view sees it.
//
// A helix of radius r and pitch P (one turn advances P along its axis a) is
// the curve c(s) + r e(s): its centre c moves along a by ds cos(alpha) per
// arc length ds, and the unit radial e (square to a) turns about a by
// h ds sin(alpha) / r, with tan(alpha) = 2 pi r / P the helix angle between
// the strand and its axis and h = +1 (right-handed: e turns anticlockwise
// about a seen from the tip) or -1. Bao & Qi fit hair with such pieces
// (Sec. V-A, the floating tangents' helical elements; their curvature
// r / (r^2 + c^2) and torsion c / (r^2 + c^2) with c = P / 2 pi).
//
// HelixGuide starts the helix from a strand's point and tangent (the point
// lies on it; the tangent's part square to the axis fixes where the centre
// lies) and then gives, step by step, the direction towards the helix's next
// point: a strand that strays from it (the head pushes it out) is drawn back,
// and the centre moves along the axis given at each step, so the helix bends
// as the field does.
//
// Units: mm and radians; directions unit vectors in the points' frame.
#pragma once

#include <Eigen/Core>

#include "core/status.h"

namespace hairrig {

struct Curl {
  double radius_mm = 0;  // 0: no curl (a straight strand)
  double pitch_mm = 0;
  int handedness = 1;  // +1 right-handed, -1 left-handed

  bool curly() const { return radius_mm > 0 && pitch_mm > 0; }
  // Ok for no curl (both 0) or a finite positive radius and pitch with
  // handedness +-1; else InvalidArgument naming the field.
  Status Check() const;
  // tan(alpha) = 2 pi r / P, in [0, pi / 2).
  double HelixAngle() const;
};

class HelixGuide {
 public:
  explicit HelixGuide(double step_mm) : step_mm_(step_mm) {}

  // Starts a helix (`curl` must be curly()) through `p` with the strand's direction `tangent` about
  // `axis` (unit; the strand's way along it is the sign of tangent . axis).
  // A tangent along the axis leaves the centre's side undetermined: it is
  // then taken square to the axis in a fixed way.
  void Start(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent, const Eigen::Vector3f& axis,
             const Curl& curl);
  // Starts the helix through `p` with the strand's unit `tangent`, on the
  // bend of the stretch it has just followed: `bend_tangent` and
  // `bend_normal` are that stretch's unit tangent and principal normal (the
  // side it turns to) at some point of it. A helix's axis is the same all
  // along it, cos(alpha) t + h sin(alpha) (t x n) at every point (the
  // Darboux vector's direction, Frenet-Serret); Start about that axis then
  // places the centre. The strand goes on the way it came, where Start about
  // another axis kinks it by the difference between its angle to that axis
  // and alpha.
  void StartOnBend(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent,
                   const Eigen::Vector3f& bend_tangent, const Eigen::Vector3f& bend_normal,
                   const Curl& curl);
  void Stop() { active_ = false; }
  bool active() const { return active_; }

  // The unit direction from `p` (the strand's last vertex) towards the
  // helix's point one step on, its centre moved along `axis` (unit, oriented
  // as at Start; flipped to it when given the other way).
  Eigen::Vector3f Next(const Eigen::Vector3f& p, const Eigen::Vector3f& axis);

  // The unit direction from `p` towards the helix's point as it stands (the
  // point Next last gave), without moving on.
  Eigen::Vector3f Towards(const Eigen::Vector3f& p) const;
  // Moves the helix's centre by `distance_mm` square to its axis, away from
  // `q` (a point the strand must not reach; Next's point moves with the
  // centre). False, and nothing moved, when q lies within a micrometre of
  // the axis.
  bool MoveCentreAwayFrom(const Eigen::Vector3f& q, double distance_mm);

  const Eigen::Vector3d& centre() const { return centre_; }
  // The axis as last moved along (unit, the strand's way along it).
  Eigen::Vector3f axis() const { return axis_.cast<float>(); }

 private:
  double step_mm_;
  bool active_ = false;
  Curl curl_;
  double cos_alpha_ = 1, sin_alpha_ = 0;
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_ = Eigen::Vector3d::UnitZ();    // the strand's way along the axis
  Eigen::Vector3d radial_ = Eigen::Vector3d::UnitX();  // e: from the centre to the strand
};

}  // namespace hairrig
