// Circles fitted to 3D points, as Luo et al. 2013 Sec. 6.1 fit arcs across
// the ends of strand segments (after Chernov 2011): a plane by principal
// components, Taubin's algebraic circle in that plane (Taubin 1991), then
// Levenberg-Marquardt on the centre, normal and radius together, minimising
// the points' geometric distances to the circle. Units mm (any length unit
// works), any frame.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hairrig {

// Fits never return a radius above this: collinear points get a circle of
// this radius through them (curvature 1e-6 /mm, straight for any purpose
// here), its centre on a perpendicular of the line in the fitted plane.
constexpr double kMaxCircleRadiusMm = 1e6;

struct Circle3 {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal =
      Eigen::Vector3d::UnitZ();  // unit; its sign is arbitrary (OrientByTraversal)
  double radius = 0;

  double Curvature() const { return radius > 0 ? 1.0 / radius : 0.0; }
  // The distance from p to the nearest point of the circle.
  double Distance(const Eigen::Vector3d& p) const;
};

// Taubin's fit of the circle |q - center| = radius to 2D points: the
// algebraic circle a |q|^2 + b.q + c = 0 minimising sum of squared algebraic
// distances under the constraint mean |gradient|^2 = 1, which is the exact
// straight line when the points are collinear (the radius then
// kMaxCircleRadiusMm). False for fewer than 3 points or all points in one place.
bool FitCircleTaubin(const std::vector<Eigen::Vector2d>& points, Eigen::Vector2d* center,
                     double* radius);

// The 3D fit (plane, Taubin, Levenberg-Marquardt). Returns the RMS distance of
// the points to the circle (mm); +infinity, with *circle untouched, for
// fewer than 3 points or points all in one place.
double FitCircle3(const std::vector<Eigen::Vector3d>& points, Circle3* circle);

// The signed swept area of the polyline `points` about the circle's centre:
// sum_i ((q_i - c) x (q_{i+1} - c)) . n. Positive when the points run
// counter-clockwise about the normal.
double SweptArea(const std::vector<Eigen::Vector3d>& points, const Circle3& circle);

// Flips circle->normal so that `points`, in order, run counter-clockwise
// about it (SweptArea > 0): normals of arcs fitted to pieces traversed the
// same way are then comparable.
void OrientByTraversal(const std::vector<Eigen::Vector3d>& points, Circle3* circle);

// Luo Sec. 6.1 criterion (d): eta = 1 - |V / V0| with V the signed and V0 the
// unsigned sweep sum_i ((q_{i+1} - c) x (q_i - c)) . n over the polyline:
// 0 when the points run one way round the centre, up to 1 when they double
// back over themselves. 0 for fewer than 2 points.
double SweepOverlap(const std::vector<Eigen::Vector3d>& points, const Circle3& circle);

}  // namespace hairrig
