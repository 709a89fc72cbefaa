// One view's tag detections matched to the calibration box model, and the
// view's pose from them: the initialisation of the bundle
// adjustment, which needs no hand-tuned guess.
//
// Matching: a detection whose id is not on the box, or an id seen twice in one
// view, is reported and left out. Pose: the corners are undistorted with the
// camera's intrinsics; every tag alone gives two pose hypotheses (IPPE for a
// planar square, calibration/planar_pose.h), the one most tags agree with
// wins (a RANSAC over tags), Levenberg-Marquardt refines it on those tags, and a tag whose
// reprojection RMS under the refined pose is too large is reported and left
// out before a last refinement. Pixels in the OpenCV convention
// (core/transform.h), box frame in mm (core/calib_box.h).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "calibration/apriltag_detector.h"
#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

struct TagObservation {
  int id = -1;
  std::array<Eigen::Vector2d, 4> corners_px;      // kTagCornerSigns order
  std::array<Eigen::Vector3d, 4> corners_box_mm;  // the same corners on the box
};

struct RejectedTag {
  int id = -1;
  std::string reason;
};

struct ViewObservations {
  std::vector<TagObservation> tags;
  std::vector<RejectedTag> rejected;
};

// Never fails: what cannot be used is in `rejected` with the reason.
ViewObservations MatchToBox(const std::vector<TagDetection>& detections, const CalibBox& box);

struct ViewPoseOptions {
  double ransac_threshold_px = 3.0;  // tag reprojection RMS of an inlier of a hypothesis
  double max_tag_rms_px = 1.5;       // a tag above this after the fit is left out
  int min_tags = 2;                  // one planar tag gives an ambiguous pose
  // How far the box's tags may be off their model (mm, one standard deviation,
  // a box as built): both thresholds above then apply to a tag's RMS beyond 3
  // such deviations at the tag's distance. 0: the model is exact.
  double box_tolerance_mm = 0;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

struct ViewPose {
  Rigid3d cam_from_box;
  double rms_px = 0;  // RMS of the corners' 2D reprojection error, tags used, pixels
  int tags_used = 0;
  std::vector<RejectedTag> rejected;  // the matching's and the fit's
};

// FailedPrecondition when fewer than `min_tags` usable tags remain (the
// message says how many and why the others were left out); InvalidArgument
// for invalid intrinsics or options (ViewPoseOptions::Check).
Result<ViewPose> EstimateViewPose(const ViewObservations& observations,
                                  const CameraIntrinsics& intrinsics,
                                  const ViewPoseOptions& options = {});

}  // namespace hairrig
