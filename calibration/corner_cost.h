// Ceres cost terms shared by the calibration's solvers: the pixel residual of
// a known point of the box (or of one of its faces) seen by a camera with
// intrinsics in CameraIntrinsics::kParamNames order (core/camera_model.h).
// Header-only templates for ceres::AutoDiffCostFunction.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/camera_model.h"

namespace hairrig {

template <typename T>
using CornerVec3 = Eigen::Matrix<T, 3, 1>;

// Projection of a camera-frame point minus the observed pixel (px).
template <typename T>
bool ProjectResidual(const T* intrinsics, const CornerVec3<T>& p_cam,
                     const Eigen::Vector2d& observed, T* residual) {
  T uv[2];
  ProjectCamPoint(intrinsics, p_cam.data(), uv);
  residual[0] = uv[0] - T(observed.x());
  residual[1] = uv[1] - T(observed.y());
  return true;
}

// A point (mm, model frame) seen under one pose: cam_from_model as a
// quaternion block (Eigen order x, y, z, w) and a translation block (mm).
struct PosedCorner {
  Eigen::Vector2d observed;
  Eigen::Vector3d p_model;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_model, const T* t_cam_from_model,
                  T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_from_model);
    const CornerVec3<T> p_cam =
        q * p_model.cast<T>() + Eigen::Map<const CornerVec3<T>>(t_cam_from_model);
    return ProjectResidual(intrinsics, p_cam, observed, residual);
  }
};

}  // namespace hairrig
