#include "reconstruction/helix_guide.h"

#include <Eigen/Geometry>
#include <cmath>

namespace hairrig {

Status Curl::Check() const {
  if (radius_mm == 0 && pitch_mm == 0) return Status::Ok();
  if (!(std::isfinite(radius_mm) && radius_mm > 0 && std::isfinite(pitch_mm) && pitch_mm > 0))
    return InvalidArgument("a curl's radius_mm and pitch_mm must be finite and positive");
  if (handedness != 1 && handedness != -1)
    return InvalidArgument("a curl's handedness must be +1 (right) or -1 (left)");
  return Status::Ok();
}

double Curl::HelixAngle() const {
  if (!curly()) return 0;
  return std::atan2(2 * M_PI * radius_mm, pitch_mm);
}

namespace {

// `v` made square to unit `a` and unit; `fallback` when it lies along `a`.
Eigen::Vector3d SquareTo(const Eigen::Vector3d& v, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d across = v - v.dot(a) * a;
  const double n = across.norm();
  return n > 1e-6 ? Eigen::Vector3d(across / n) : fallback;
}

}  // namespace

void HelixGuide::Start(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent,
                       const Eigen::Vector3f& axis, const Curl& curl) {
  curl_ = curl;
  const double alpha = curl.HelixAngle();
  cos_alpha_ = std::cos(alpha);
  sin_alpha_ = std::sin(alpha);
  const Eigen::Vector3d t = tangent.cast<double>().normalized();
  axis_ = axis.cast<double>().normalized();
  if (t.dot(axis_) < 0) axis_ = -axis_;
  // The tangent is cos(alpha) a + sin(alpha) b with b = h (a x e) its part
  // square to the axis; so e = -h (a x b).
  const Eigen::Vector3d b = SquareTo(t, axis_, axis_.unitOrthogonal());
  radial_ = -static_cast<double>(curl.handedness) * axis_.cross(b);
  centre_ = p.cast<double>() - curl.radius_mm * radial_;
  active_ = true;
}

void HelixGuide::StartOnBend(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent,
                             const Eigen::Vector3f& bend_tangent,
                             const Eigen::Vector3f& bend_normal, const Curl& curl) {
  const double alpha = curl.HelixAngle();
  const Eigen::Vector3d t = bend_tangent.cast<double>().normalized();
  const Eigen::Vector3d n = SquareTo(bend_normal.cast<double>(), t, t.unitOrthogonal());
  const Eigen::Vector3d axis = std::cos(alpha) * t + curl.handedness * std::sin(alpha) * t.cross(n);
  Start(p, tangent, axis.normalized().cast<float>(), curl);
}

Eigen::Vector3f HelixGuide::Next(const Eigen::Vector3f& p, const Eigen::Vector3f& axis) {
  Eigen::Vector3d a = axis.cast<double>().normalized();
  if (!a.allFinite()) a = axis_;
  if (a.dot(axis_) < 0) a = -a;
  axis_ = a;
  radial_ = SquareTo(radial_, a, a.unitOrthogonal());
  centre_ += step_mm_ * cos_alpha_ * a;
  const double turn = curl_.handedness * step_mm_ * sin_alpha_ / curl_.radius_mm;
  radial_ = std::cos(turn) * radial_ + std::sin(turn) * a.cross(radial_);
  return Towards(p);
}

Eigen::Vector3f HelixGuide::Towards(const Eigen::Vector3f& p) const {
  const Eigen::Vector3d to_next = centre_ + curl_.radius_mm * radial_ - p.cast<double>();
  const double n = to_next.norm();
  return (n > 1e-9 ? Eigen::Vector3d(to_next / n) : axis_).cast<float>();
}

bool HelixGuide::MoveCentreAwayFrom(const Eigen::Vector3f& q, double distance_mm) {
  Eigen::Vector3d away = centre_ - q.cast<double>();
  away -= away.dot(axis_) * axis_;
  const double n = away.norm();
  if (n <= 1e-3) return false;
  centre_ += (distance_mm / n) * away;
  return true;
}

}  // namespace hairrig
