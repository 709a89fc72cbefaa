#include "core/camera_model.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

namespace hairrig {

CameraIntrinsics CameraIntrinsics::FromParams(const double* p, int width_px, int height_px) {
  CameraIntrinsics c;
  c.width_px = width_px;
  c.height_px = height_px;
  c.fx_px = p[0];
  c.fy_px = p[1];
  c.cx_px = p[2];
  c.cy_px = p[3];
  c.k1 = p[4];
  c.k2 = p[5];
  c.p1 = p[6];
  c.p2 = p[7];
  c.k3 = p[8];
  return c;
}

Status CameraIntrinsics::Check() const {
  const auto params = ToParams();
  for (int i = 0; i < kNumParams; ++i) {
    if (!std::isfinite(params[i])) {
      return InvalidArgument(std::string("camera intrinsics: ") + kParamNames[i] +
                             " is not a finite number");
    }
  }
  if (width_px <= 0 || height_px <= 0)
    return InvalidArgument("camera intrinsics: image size must be positive");
  if (fx_px <= 0 || fy_px <= 0)
    return InvalidArgument("camera intrinsics: fx_px and fy_px must be positive");
  // 1000 x the long side is a field of view under 0.06 deg: beyond any lens.
  const double max_focal_px = 1000.0 * std::max(width_px, height_px);
  if (fx_px > max_focal_px || fy_px > max_focal_px) {
    return InvalidArgument(
        "camera intrinsics: fx_px and fy_px must be at most 1000 x the image's long side (" +
        std::to_string(static_cast<long long>(max_focal_px)) +
        " px; a field of view under 0.06 deg "
        "is no lens): check the file or the lens' focal length");
  }
  if (cx_px < 0 || cx_px > width_px || cy_px < 0 || cy_px > height_px) {
    return InvalidArgument(
        "camera intrinsics: principal point (cx_px, cy_px) lies outside the image");
  }
  return Status::Ok();
}

bool ProjectChecked(const CameraIntrinsics& camera, const Eigen::Vector3d& p_cam,
                    Eigen::Vector2d* uv) {
  if (!(p_cam.z() > 1e-9)) return false;
  *uv = Project(camera, p_cam);
  return true;
}

Eigen::Vector2d Project(const CameraIntrinsics& camera, const Eigen::Vector3d& p_cam) {
  const auto params = camera.ToParams();
  Eigen::Vector2d uv;
  ProjectCamPoint(params.data(), p_cam.data(), uv.data());
  return uv;
}

Result<Eigen::Vector2d> UndistortPixel(const CameraIntrinsics& camera, const Eigen::Vector2d& uv) {
  const auto params = camera.ToParams();
  const Eigen::Vector2d target((uv.x() - camera.cx_px) / camera.fx_px,
                               (uv.y() - camera.cy_px) / camera.fy_px);
  Eigen::Vector2d x = target;  // the undistorted point starts at the distorted one
  for (int iter = 0; iter < 30; ++iter) {
    // Numerical Jacobian is accurate enough here and keeps one copy of the model.
    double xd, yd;
    DistortNormalized(params.data(), x.x(), x.y(), &xd, &yd);
    const Eigen::Vector2d residual(xd - target.x(), yd - target.y());
    if (residual.norm() < 1e-14) return x;
    constexpr double h = 1e-7;
    Eigen::Matrix2d jac;
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d xh = x;
      xh[c] += h;
      double xdh, ydh;
      DistortNormalized(params.data(), xh.x(), xh.y(), &xdh, &ydh);
      jac(0, c) = (xdh - xd) / h;
      jac(1, c) = (ydh - yd) / h;
    }
    if (std::abs(jac.determinant()) < 1e-12) break;
    x -= jac.inverse() * residual;
    if (!x.allFinite()) break;
  }
  double xd, yd;
  DistortNormalized(params.data(), x.x(), x.y(), &xd, &yd);
  if (x.allFinite() && std::hypot(xd - target.x(), yd - target.y()) < 1e-10) return x;
  return OutOfRange("pixel (" + std::to_string(uv.x()) + ", " + std::to_string(uv.y()) +
                    ") cannot be undistorted: the distortion model does not invert there");
}

}  // namespace hairrig
