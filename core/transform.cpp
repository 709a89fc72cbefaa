#include "core/transform.h"

#include <algorithm>
#include <cmath>

namespace hairrig {

Rigid3d WorldFromTurntable(double theta_deg) {
  return Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(DegToRad(theta_deg), Eigen::Vector3d::UnitZ())),
      Eigen::Vector3d::Zero());
}

Rigid3d LookAt(const Eigen::Vector3d& eye_mm, const Eigen::Vector3d& target_mm,
               const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target_mm - eye_mm).normalized();  // forward
  Eigen::Vector3d x = z.cross(up);                              // right (image +x)
  if (x.norm() < 1e-9) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);  // image down
  Eigen::Matrix3d world_from_cam_rot;
  world_from_cam_rot << x, y, z;
  const Rigid3d world_from_cam(world_from_cam_rot, eye_mm);
  return world_from_cam.Inverse();
}

double RotationDifferenceDeg(const Rigid3d& a, const Rigid3d& b) {
  const Eigen::Quaterniond d = (a.rotation.conjugate() * b.rotation).normalized();
  // atan2 of the sine and cosine of the half angle keeps full precision for
  // small angles, where 2 acos(|w|) rounds anything under about 3e-8 rad to 0.
  return RadToDeg(2.0 * std::atan2(d.vec().norm(), std::abs(d.w())));
}

}  // namespace hairrig
