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

// A model-frame point in the camera frame under cam_from_model as a
// quaternion block (Eigen order x, y, z, w) and a translation block (mm).
template <typename T>
CornerVec3<T> PosedPoint(const T* q_cam_from_model, const T* t_cam_from_model,
                         const CornerVec3<T>& p_model) {
  const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_from_model);
  return q * p_model + Eigen::Map<const CornerVec3<T>>(t_cam_from_model);
}

// A point (mm, model frame) seen under one pose (PosedPoint).
struct PosedCorner {
  Eigen::Vector2d observed;
  Eigen::Vector3d p_model;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_model, const T* t_cam_from_model,
                  T* residual) const {
    return ProjectResidual(
        intrinsics,
        PosedPoint(q_cam_from_model, t_cam_from_model, CornerVec3<T>(p_model.cast<T>())), observed,
        residual);
  }
};

}  // namespace hairrig
