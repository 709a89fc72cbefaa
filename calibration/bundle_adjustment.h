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
//
// Box refinement (BundleAdjustmentOptions::box_tolerance not zero): the box as
// built (core/calib_box.h) is solved with the cameras. Each observed tag's
// place (du, dv mm) and turn in its face, and each face's offset along its
// normal and tilts about u and v, are parameters held towards the input box by
// Gaussian priors with the tolerance's standard deviations (or the input box's
// own, where it states them), weighed against the corner noise like the
// intrinsics' priors. Gauge, fixed explicitly: the observed tags' corners keep
// their mean position and mean orientation, so the refinement cannot move or
// turn the box as a whole (the box pose does that).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "calibration/view_pose.h"
#include "core/calib_box.h"
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
  // Box refinement's priors (see above); all zero: the box is taken as exact.
  BoxTolerance box_tolerance;

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
  // The box the views' tags are on (matched by id); needed for box refinement.
  CalibBox box;
};

// What box refinement made of one observed tag: how far it moved in its face
// from the input box (mm along the face's u and v) and turned about its normal
// (deg), with standard deviations (NaN when the covariance is rank deficient).
struct TagRefinement {
  int id = -1;
  int views = 0;  // views that observed it
  Eigen::Vector2d moved_mm = Eigen::Vector2d::Zero();
  double turned_deg = 0;
  Eigen::Vector2d moved_sd_mm = Eigen::Vector2d::Constant(NAN);
  double turned_sd_deg = NAN;
};

// The same for a face holding observed tags: moved along its normal (mm) and
// tilted about its u and v axes (deg).
struct FaceRefinement {
  int face = -1;  // index into CalibBox::faces
  double moved_mm = 0, tilted_u_deg = 0, tilted_v_deg = 0;
  double moved_sd_mm = NAN, tilted_sd_deg = NAN;  // tilted: the larger of the two
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
  // With box refinement: the input box with its observed tags and faces as
  // solved (standard deviations included, PlaceTags applied), and the moves.
  bool box_refined = false;
  CalibBox box;
  std::vector<TagRefinement> tag_moves;    // by tag id
  std::vector<FaceRefinement> face_moves;  // by face index
};

// InvalidArgument for bad options (BundleAdjustmentOptions::Check), a view of
// an unknown camera, a camera without views, invalid intrinsics, no
// observation at all, or (with box refinement) a tag the input box does not
// have; the message names them.
Result<BundleAdjustmentResult> RunBundleAdjustment(const BundleAdjustmentInput& input,
                                                   const BundleAdjustmentOptions& options);

}  // namespace hairrig
