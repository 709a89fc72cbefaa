// Pinhole camera with Brown-Conrady distortion (k1, k2, p1, p2, k3), the model
// of OpenCV's calib3d, so that parameters move between the two unchanged.
//
// Projection of a point p_cam (mm, camera frame, see core/transform.h):
//   x = X/Z, y = Y/Z, r2 = x^2 + y^2
//   radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
//   yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
//   u = fx xd + cx, v = fy yd + cy          (pixels, centre of pixel (0,0) at 0,0)
//
// The templates take the parameters as a flat array in the order of
// CameraIntrinsics::kParamNames so that Ceres can differentiate through them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>

#include "core/status.h"

namespace hairrig {

struct CameraIntrinsics {
  static constexpr int kNumParams = 9;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3"};

  int width_px = 0;
  int height_px = 0;
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  std::array<double, kNumParams> ToParams() const {
    return {fx_px, fy_px, cx_px, cy_px, k1, k2, p1, p2, k3};
  }
  static CameraIntrinsics FromParams(const double* params, int width_px, int height_px);

  // Finite values, positive focal lengths and image size, principal point
  // inside the image. The message names the offending parameter.
  Status Check() const;
};

// Distorts normalised coordinates (x, y) = (X/Z, Y/Z). `params` as ToParams().
template <typename T>
inline void DistortNormalized(const T* params, const T& x, const T& y, T* xd, T* yd) {
  const T& k1 = params[4];
  const T& k2 = params[5];
  const T& p1 = params[6];
  const T& p2 = params[7];
  const T& k3 = params[8];
  const T r2 = x * x + y * y;
  const T radial = T(1) + r2 * (k1 + r2 * (k2 + r2 * k3));
  *xd = x * radial + T(2) * p1 * x * y + p2 * (r2 + T(2) * x * x);
  *yd = y * radial + p1 * (r2 + T(2) * y * y) + T(2) * p2 * x * y;
}

// Projects a camera-frame point to pixels. No check of Z > 0: callers that may
// see points behind the camera use ProjectChecked.
template <typename T>
inline void ProjectCamPoint(const T* params, const T* p_cam, T* uv) {
  const T x = p_cam[0] / p_cam[2];
  const T y = p_cam[1] / p_cam[2];
  T xd, yd;
  DistortNormalized(params, x, y, &xd, &yd);
  uv[0] = params[0] * xd + params[2];
  uv[1] = params[1] * yd + params[3];
}

// Projects a camera-frame point; false if it is behind (or on) the image plane.
bool ProjectChecked(const CameraIntrinsics& camera, const Eigen::Vector3d& p_cam,
                    Eigen::Vector2d* uv);
Eigen::Vector2d Project(const CameraIntrinsics& camera, const Eigen::Vector3d& p_cam);

// Inverts the distortion: pixel -> normalised coordinates (x, y) with the ray
// (x, y, 1) in the camera frame. Newton iteration; fails (OutOfRange) where the
// distortion model is not invertible, e.g. far outside the image with strong k1.
Result<Eigen::Vector2d> UndistortPixel(const CameraIntrinsics& camera, const Eigen::Vector2d& uv);

}  // namespace hairrig
