#include "calibration/turntable_axis.h"

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <string>

namespace hairrig {

namespace {

struct Circle {
  Eigen::Vector3d center, normal;
  double radius = 0, rms = 0;
};

// Plane through the points (least squares), then the circle in it (Kasa fit).
Circle FitCircle(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::MatrixXd centred(points.size(), 3);
  for (size_t i = 0; i < points.size(); ++i)
    centred.row(static_cast<Eigen::Index>(i)) = (points[i] - mean).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
  Circle c;
  c.normal = svd.matrixV().col(2);
  const Eigen::Vector3d u = svd.matrixV().col(0), v = svd.matrixV().col(1);
  Eigen::MatrixXd a(points.size(), 3);
  Eigen::VectorXd b(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const double x = (points[i] - mean).dot(u), y = (points[i] - mean).dot(v);
    a.row(static_cast<Eigen::Index>(i)) << 2 * x, 2 * y, 1;
    b[static_cast<Eigen::Index>(i)] = x * x + y * y;
  }
  const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);
  c.center = mean + s[0] * u + s[1] * v;
  c.radius = std::sqrt(std::max(0.0, s[2] + s[0] * s[0] + s[1] * s[1]));
  double sq = 0;
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - c.center;
    const double in_plane = (d - d.dot(c.normal) * c.normal).norm();
    sq += std::pow(in_plane - c.radius, 2) + std::pow(d.dot(c.normal), 2);
  }
  c.rms = std::sqrt(sq / static_cast<double>(points.size()));
  return c;
}

}  // namespace

Result<TurntableAxisFit> FitTurntableAxis(const std::vector<CalibrationView>& views,
                                          double height_mm, double yaw_deg) {
  // Camera centres in the box frame, per camera, ordered by turntable angle.
  std::map<int, std::map<double, Eigen::Vector3d>> centres;
  for (const CalibrationView& v : views) {
    if (v.tags.empty()) continue;
    centres[v.camera][v.turntable_deg] = v.cam_from_box_init.Inverse().translation;
  }
  int best = -1;
  size_t most = 0;
  for (const auto& [camera, by_angle] : centres) {
    const double span = by_angle.empty() ? 0 : by_angle.rbegin()->first - by_angle.begin()->first;
    if (by_angle.size() >= 3 && span > 10 && by_angle.size() > most) {
      most = by_angle.size();
      best = camera;
    }
  }
  if (best < 0) {
    return FailedPrecondition(
        "turntable axis: no camera sees the box at 3 or more stops spanning over 10 deg");
  }
  std::vector<Eigen::Vector3d> points;
  for (const auto& [angle, p] : centres[best]) points.push_back(p);
  const Circle circle = FitCircle(points);
  // The camera moves by -theta about the axis: pick the normal's sign from the
  // turn between the first two stops.
  const Eigen::Vector3d first = points[0] - circle.center, second = points[1] - circle.center;
  Eigen::Vector3d z = circle.normal;
  if (first.cross(second).dot(z) > 0) z = -z;
  Eigen::Vector3d x = Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitX().dot(z) * z;
  if (x.norm() < 1e-3) x = Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitY().dot(z) * z;
  x.normalize();
  x = Eigen::AngleAxisd(-yaw_deg * M_PI / 180, z) *
      x;  // the box's x axis lies yaw_deg past the turntable's
  Eigen::Matrix3d box_from_turntable_rotation;
  box_from_turntable_rotation << x, z.cross(x), z;
  // Origin on the axis, placed so that the box origin sits at `height_mm`.
  const Eigen::Vector3d origin = circle.center + (circle.center.dot(z) * -1 - height_mm) * z;
  TurntableAxisFit fit;
  fit.turntable_from_box = Rigid3d(box_from_turntable_rotation, origin).Inverse();
  fit.camera = best;
  fit.circle_rms_mm = circle.rms;
  fit.radius_mm = circle.radius;
  return fit;
}

}  // namespace hairrig
