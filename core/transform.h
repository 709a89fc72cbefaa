// Rigid transforms and the frame conventions of the whole project.
//
// CONVENTIONS (written once, here):
// - A transform is named `a_from_b`: it maps coordinates expressed in frame b to
//   frame a, so `p_a = a_from_b * p_b` and `a_from_c = a_from_b * b_from_c`.
// - Lengths are millimetres everywhere (world, box, strands, camera centres);
//   angles in public APIs are degrees unless a name ends in `_rad`.
// - Frames:
//   world      fixed to the rig; origin at the turntable centre on its top
//              surface, +z up along the turntable axis.
//   turntable  rotates with the turntable: turntable_from_world is a rotation
//              by -theta about +z, theta the turntable angle (right-handed, deg).
//   box        the calibration box, rigid on the turntable; origin at the box
//              centre, axes along its edges (etc/calib-box.yaml).
//   cam        OpenCV camera frame: +x right, +y down in the image, +z forward
//              along the optical axis.
//   image      pixels; (0,0) is the CENTRE of the top-left pixel (OpenCV).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hairrig {

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& r, const Eigen::Vector3d& t)
      : rotation(r.normalized()), translation(t) {}
  Rigid3d(const Eigen::Matrix3d& r, const Eigen::Vector3d& t)
      : rotation(Eigen::Quaterniond(r).normalized()), translation(t) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  Rigid3d operator*(const Rigid3d& other) const {
    return Rigid3d(rotation * other.rotation, rotation * other.translation + translation);
  }
  Rigid3d Inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return Rigid3d(inv, -(inv * translation));
  }
  Eigen::Matrix3d RotationMatrix() const { return rotation.toRotationMatrix(); }
  Eigen::Matrix<double, 3, 4> ToMatrix3x4() const {
    Eigen::Matrix<double, 3, 4> m;
    m << RotationMatrix(), translation;
    return m;
  }
  // Angle-axis vector (rad) of the rotation, as OpenCV's rvec and Ceres use it.
  Eigen::Vector3d AngleAxis() const {
    const Eigen::AngleAxisd aa(rotation);
    return aa.angle() * aa.axis();
  }
  static Rigid3d FromAngleAxis(const Eigen::Vector3d& rvec, const Eigen::Vector3d& t) {
    const double angle = rvec.norm();
    if (angle < 1e-300) return Rigid3d(Eigen::Quaterniond::Identity(), t);
    return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle, rvec / angle)), t);
  }
};

// world_from_turntable at turntable angle theta (deg): rotation about world +z.
Rigid3d WorldFromTurntable(double theta_deg);

// A camera pose that looks from `eye_mm` towards `target_mm` with image "up"
// roughly along `up` (world). Returns cam_from_world.
Rigid3d LookAt(const Eigen::Vector3d& eye_mm, const Eigen::Vector3d& target_mm,
               const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// Rotation angle (deg) of a_from_b.rotation^-1 * c_from_d.rotation: the
// difference between two rotations.
double RotationDifferenceDeg(const Rigid3d& a, const Rigid3d& b);

constexpr double kPi = 3.14159265358979323846;
inline double DegToRad(double deg) { return deg * kPi / 180.0; }
inline double RadToDeg(double rad) { return rad * 180.0 / kPi; }

}  // namespace hairrig
