// A calibration against the simulated rig's ground truth, for
// `hairrig eval calibration` and `hairrig eval intrinsics`:
//
//   calibration  a capture's calibration.json (calibration/calibration_io.h)
//                against its ground_truth/ (core/truth_maps.h): per solved view
//                the rotation error of cam_from_box (deg) and the error of the
//                camera centre (mm), both in the frame of the true tags
//                (EvaluationBoxes); per camera the focal
//                length error (%, the worse of fx and fy) and the principal
//                point's (px); for the bundle adjustment's result and for the
//                initial poses and intrinsics before it. Besides: the corner
//                noise of the frames (the used detections against the true
//                projections of the box's tag corners), which the reprojection
//                RMS is compared with, and the observed over the predicted
//                errors (calibration/uncertainty_check.h).
//   intrinsics   one camera's ChArUco calibration (DIR/intrinsics.json from
//                `hairrig calibrate-intrinsics`) against the true intrinsics
//                `hairrig sim charuco` wrote (DIR/ground_truth.json), each
//                parameter's error also in its standard deviations.
//
// Simulation-only: production stages never take a ground truth as input.
#pragma once

#include <array>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calibration/calibration_io.h"
#include "calibration/uncertainty_check.h"
#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/status.h"
#include "core/truth_maps.h"

namespace hairrig {

// Errors of one kind, one value per view or camera.
struct ErrorSpread {
  std::vector<double> values;
  // {"median": the upper median, "max": ...}; both null when there are no values.
  nlohmann::json ToJson() const;
};

// One set of poses and intrinsics (the bundle adjustment's or the initial
// ones) against the truth.
struct PoseErrors {
  ErrorSpread rotation_deg;        // per view
  ErrorSpread camera_centre_mm;    // per view, the true tags' frame
  ErrorSpread focal_percent;       // per camera: 100 max(|fx / fx_true - 1|, |fy / fy_true - 1|)
  ErrorSpread principal_point_px;  // per camera
  nlohmann::json ToJson() const;
};

struct CalibrationEvaluation {
  std::string dir;         // the capture folder, as the caller named it (reported only)
  std::string mode;        // "turntable" or "free", as calibration.json says
  int views = 0;           // in calibration.json
  int views_compared = 0;  // solved and in the ground truth
  PoseErrors solved;       // the bundle adjustment's
  PoseErrors initial;      // before it
  // What the initial intrinsics came from: "Zhang per camera + per-view IPPE"
  // when any camera's came from the views, else "nominal intrinsics".
  std::string initial_source;
  ErrorSpread reprojection_rms_px;  // per solved view
  double overall_rms_px = 0;
  // RMS distance (px, per corner) of the detections the bundle adjustment used
  // from the true projections of the tag corners; nullopt when no corner of a
  // known tag was compared.
  std::optional<double> corner_noise_px;
  UncertaintyRatios uncertainty;  // over the solved views
  // The move from the calibration's box frame to the true tags' frame the
  // poses were compared in (0 when the calibration's box is the true one).
  double box_alignment_deg = 0;
  double box_alignment_mm = 0;

  // "stage": "calibration"; "solved" holds reprojection_rms_px too;
  // "rms_over_corner_noise" only with a corner noise; "box_alignment":
  // {"rotation_deg", "translation_mm"}.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// The two boxes an evaluation needs: the one the calibration's poses are in
// (its refined box, else the box it was given) and the one the images show (a
// simulated box as built, else the same). The poses are compared in the frame
// of the true tags (TruthFromEstimatedBox over the tags the calibration used),
// the detections with the true tags' projections.
struct EvaluationBoxes {
  CalibBox estimated;
  CalibBox truth;
};

// Solved views without a true pose are skipped. FailedPrecondition when no
// solved view has one, or when the two boxes have no tag in common.
Result<CalibrationEvaluation> EvaluateCalibration(const StoredCalibration& calibration,
                                                  const CaptureTruth& truth,
                                                  const EvaluationBoxes& boxes);

// The rigid transform from the box frame `estimated` defines to the one
// `truth` defines, fitted over the corners of the tags both have (least
// squares without scale, Umeyama 1991). A box's frame is fixed by its tags
// alone, so a calibration against a box as built compares with the truth in
// the frame of the true tags. `tag_ids`: the tags to fit over (the observed
// ones; the others keep their drawn place); empty: every tag. Identity when
// the boxes have no chosen tag in common (one tag's 4 corners fix the fit).
Rigid3d TruthFromEstimatedBox(const CalibBox& estimated, const CalibBox& truth,
                              const std::vector<int>& tag_ids = {});

// The true intrinsics in a ChArUco image set's ground_truth.json (format
// "hairrig-charuco-truth", sim_hw/charuco_views.h). NotFound when the file is
// absent; CorruptData naming the file and field for another format or a
// damaged file.
Result<CameraIntrinsics> ReadChArUcoTruthIntrinsics(const std::string& path);

struct IntrinsicsEvalOptions {
  std::string dir;  // holds intrinsics.json and ground_truth.json

  Status Check() const;  // InvalidArgument naming the field
};

struct IntrinsicsEvaluation {
  std::string dir;
  std::string serial;
  CameraIntrinsics truth;
  CameraIntrinsics solved;
  std::array<double, CameraIntrinsics::kNumParams> stddev{};  // kParamNames order; 0: held
  double focal_percent = 0;       // 100 max(|fx / fx_true - 1|, |fy / fy_true - 1|)
  double principal_point_px = 0;  // distance from the true principal point
  // The largest |error| / stddev over the parameters (those with a stddev).
  double worst_error_in_stddev = 0;

  // "stage": "intrinsics"; "params" by name, each {truth, solved, error, stddev, error_in_stddev}.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: a file missing or damaged (named), an intrinsics.json that is not
// one camera's `calibrate-intrinsics` result.
Result<IntrinsicsEvaluation> EvaluateIntrinsicsFolder(const IntrinsicsEvalOptions& options);

}  // namespace hairrig
