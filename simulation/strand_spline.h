// A strand as a smooth curve: a C1 cubic Bezier spline through its points
// (Catmull-Rom tangents, chord-length parameterised), evaluated by arc length.
// The spline approximation step of Bao & Qi 2017, Algorithm 1, line 2.
// Millimetres.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/status.h"

namespace hairrig {

class StrandSpline {
 public:
  // InvalidArgument for fewer than 2 points, non-finite points (named by
  // vertex), or a strand of zero length; the message does not name the
  // strand, the caller adds it. Consecutive duplicate points are dropped.
  static Result<StrandSpline> Create(const std::vector<Eigen::Vector3d>& points_mm);

  double length_mm() const { return cumulative_mm_.back(); }
  Eigen::Vector3d PointAt(double s_mm) const;
  Eigen::Vector3d TangentAt(double s_mm) const;  // unit
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  // The angle (radians) the tangent turns through along the whole strand,
  // summed between the tangents at consecutive points.
  double turning_rad() const { return turning_rad_; }

 private:
  // Segment index and Bezier parameter u in [0, 1] at arc length s.
  void Locate(double s_mm, int* segment, double* u) const;
  std::array<Eigen::Vector3d, 4> Controls(
      int segment) const;  // the segment's Bezier control points
  Eigen::Vector3d Bezier(int segment, double u) const;
  // B'(u) = 3 (d0 + u (q1 + u q2)) on a segment, from its control polygon's
  // legs d0, d1, d2: q1 = 2 (d1 - d0), q2 = d0 - 2 d1 + d2.
  struct Derivative {
    Eigen::Vector3d d0, q1, q2;
    Eigen::Vector3d At(double u) const { return 3 * (d0 + u * (q1 + u * q2)); }
  };
  Derivative DerivativeOf(int segment) const;

  std::vector<Eigen::Vector3d> points_;
  std::vector<Eigen::Vector3d> control_;  // 3 per segment: p_i, c1, c2 (p_{i+1} is the next start)
  std::vector<double> cumulative_mm_;     // arc length at each table sample
  std::vector<double> table_u_;           // segment + u at each table sample
  double turning_rad_ = 0;
};

}  // namespace hairrig
