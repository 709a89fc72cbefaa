// Bundle adjustment of a capture's views from the calibration box (docs/design.md
// section 5), in Ceres with a robust (Huber) loss.
//
// Mode `turntable`: camera c fixed in the world, the box rigid on the
// turntable, one angle per stop (starting from the encoder, refined):
//   cam_from_box(v) = cam_from_world(c) * world_from_turntable(theta_s) * turntable_from_box.
// Gauge, fixed explicitly: the world's z axis is the turntable axis through
// the world origin (world_from_turntable turns about it); the first stop keeps
// its encoder angle (fixes the turn about the axis) and turntable_from_box
// keeps its initial height along the axis (the origin's height is not seen).
// Mode `free`: an independent cam_from_box per view (the box frame fixes the gauge).
//
// Per camera: the pinhole + Brown-Conrady intrinsics (core/camera_model.h),
// k3 held at its initial value (rarely observable on these lenses), or all
// held from a prior calibration (exactly, or by a Gaussian with the prior's
// standard deviations). The covariance of the estimate gives each camera's
// intrinsics standard deviations and each view's predicted pose and
// projection errors (ViewUncertainty). Millimetres, degrees, pixels.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "calibration/view_pose.h"
#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

enum class CalibrationMode { kTurntable, kFree };

struct CalibrationView {
  int camera = 0;            // index into the cameras
  int stop = 0;              // turntable stop (turntable mode)
  double turntable_deg = 0;  // the encoder's angle at that stop
  std::vector<TagObservation> tags;
  Rigid3d cam_from_box_init;  // from EstimateViewPose
};

struct BundleAdjustmentOptions {
  CalibrationMode mode = CalibrationMode::kTurntable;
  // A prior (ChArUco) calibration is trusted: the cameras stay at their
  // initial intrinsics. A camera whose prior states standard deviations
  // (BundleAdjustmentInput::prior_stddev) is held by a Gaussian prior with
  // them unless hard_prior, so that the prior's own uncertainty enters the
  // covariance; parameters with a zero standard deviation are held exactly.
  bool fix_intrinsics = false;
  bool hard_prior = false;
  double huber_px = 1.0;
  int max_iterations = 100;
  int threads = 2;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

struct BundleAdjustmentInput {
  std::vector<CameraIntrinsics> cameras;  // initial values
  std::vector<CalibrationView> views;
  Rigid3d turntable_from_box_init;  // turntable mode: nominal, from the rig config
  // Per camera (empty, or one per camera): standard deviations of the prior
  // intrinsics (kParamNames order); all zero = no stated uncertainty.
  std::vector<std::array<double, CameraIntrinsics::kNumParams>> prior_stddev;
};

// What the covariance of the estimate predicts for one view's errors, as the
// root of the expected squared error (the trace of the covariance): of
// cam_from_box's rotation (deg), of the camera centre in the box frame (mm),
// and of the projection of the view's observed corners (px, RMS over them).
// The covariances themselves are in radians^2 (rotation vector of
// estimate-to-truth, camera frame) and mm^2. NaN when the covariance is rank
// deficient. A held (prior) intrinsics block contributes nothing.
struct ViewUncertainty {
  double rotation_sd_deg = NAN;
  double centre_sd_mm = NAN;
  double projection_sd_px = NAN;
  Eigen::Matrix3d rotation_cov_rad2 = Eigen::Matrix3d::Constant(NAN);
  Eigen::Matrix3d centre_cov_mm2 = Eigen::Matrix3d::Constant(NAN);
};

using IntrinsicsCovariance =
    Eigen::Matrix<double, CameraIntrinsics::kNumParams, CameraIntrinsics::kNumParams>;

struct BundleAdjustmentResult {
  std::vector<CameraIntrinsics> cameras;
  std::vector<Rigid3d> cam_from_box;    // per view
  std::vector<Rigid3d> cam_from_world;  // per camera (turntable mode)
  Rigid3d turntable_from_box;           // turntable mode
  std::vector<double> stop_deg;     // refined angle per stop (turntable mode; NaN for unused stops)
  std::vector<double> view_rms_px;  // corner reprojection RMS per view (2D error)
  double rms_px = 0;
  // Standard deviations of each camera's intrinsics (kParamNames order; 0 for
  // held parameters) from the covariance of the estimate, with the residuals'
  // own variance (residual_sigma_px, per coordinate) as the noise model.
  std::vector<std::array<double, CameraIntrinsics::kNumParams>> intrinsics_stddev;
  // The same covariance's whole block per camera (kParamNames order; rows and
  // columns of held parameters 0; NaN when it cannot be computed).
  std::vector<IntrinsicsCovariance> intrinsics_covariance;
  std::vector<ViewUncertainty> view_uncertainty;  // per view
  double residual_sigma_px = 0;
  int iterations = 0;
  bool converged = false;
};

// InvalidArgument for bad options (BundleAdjustmentOptions::Check), a view of
// an unknown camera, a camera without views, invalid intrinsics or no
// observation at all; the message names them.
Result<BundleAdjustmentResult> RunBundleAdjustment(const BundleAdjustmentInput& input,
                                                   const BundleAdjustmentOptions& options);

}  // namespace hairrig
