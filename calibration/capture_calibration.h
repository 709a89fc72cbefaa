// A capture's calibration end to end: tags detected on every frame
// in parallel, matched to the box, intrinsics initialised (nominal values, a
// prior, or the views themselves), a pose per view, the turntable axis from
// the camera centres' circle, then the bundle adjustment. Frames that cannot
// be used are named with the reason and the rest is still solved; a camera
// whose views all fail is named and left out. Intrinsics held at a prior are
// then tested against what the views alone support (calibration/prior_check.h).
//
// The library sees image files and numbers, never a device or a rig config;
// rig/ builds the input from a capture folder. Frames as in
// calibration/bundle_adjustment.h; millimetres, degrees, pixels.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calibration/bundle_adjustment.h"
#include "calibration/prior_check.h"
#include "calibration/view_pose.h"
#include "core/calib_box.h"

namespace hairrig {

struct CalibrationCamera {
  std::string name;
  std::string serial;
  int width_px = 0, height_px = 0;
  // Starting values (the lens and sensor data sheet), or the prior when
  // CaptureCalibrationOptions::fix_intrinsics; solved from the views when absent.
  std::optional<CameraIntrinsics> nominal;
  // Standard deviations of a prior's values (kParamNames order; all 0 when
  // unknown): with fix_intrinsics they hold the camera by a Gaussian prior.
  std::array<double, CameraIntrinsics::kNumParams> nominal_stddev{};
  // Where the prior came from (its file), for the messages that name it.
  std::string prior_source;
};

struct CalibrationFrame {
  std::string path;  // image file to read
  std::string name;  // as the capture names it (frames/000_SERIAL.png)
  int view = 0;
  int camera = 0;  // index into CaptureCalibrationInput::cameras
  int stop = 0;
  double turntable_deg = 0;  // measured by the encoder
  // Tags already detected and matched (during the capture, through the frame
  // sink): the image is then not read again.
  std::optional<ViewObservations> observations;
  // Not empty: why the frame must not be used (its file does not match the
  // checksum the capture recorded); the frame is reported as failed with it.
  std::string unusable;
};

struct CaptureCalibrationInput {
  std::vector<CalibrationCamera> cameras;
  std::vector<CalibrationFrame> frames;
  CalibBox box;
  std::string box_source;  // the box's file, for the report
  // Height of the box origin along the turntable axis (turntable mode): the
  // cameras cannot see it, the rig config gives it.
  double box_height_mm = 0;
  // The box's turn about the turntable axis (deg, +z right-handed) from the
  // turntable's x axis to the box's: the cameras cannot see where the
  // turntable's azimuth zero is, the rig config says how the box is mounted.
  // The solved turntable frame is the rig's, so that what the rig config
  // places in it (the head) lines up with what is reconstructed in it.
  double box_yaw_deg = 0;
};

struct CaptureCalibrationOptions {
  CalibrationMode mode = CalibrationMode::kTurntable;
  bool fix_intrinsics = false;  // hold every camera at its `nominal` (a prior calibration)
  bool hard_prior =
      false;        // ... exactly, ignoring nominal_stddev (BundleAdjustmentOptions::hard_prior)
  int threads = 2;  // detection and Ceres
  TagDetectorOptions detector;
  ViewPoseOptions pose;
  double huber_px = 1.0;
  // With fix_intrinsics: solve the views once more with free intrinsics and
  // test each camera's prior against them (CameraCalibration::prior_check).
  bool check_priors = true;
  PriorCheckOptions prior_check;
  // The box refined with the cameras (calibration/bundle_adjustment.h), held
  // to the input box with these tolerances; all zero: the box is taken as exact.
  BoxTolerance box_tolerance = kHandBuiltBoxTolerance;

  // InvalidArgument naming the field (detector.*, pose.* and prior_check.*
  // for the nested ones) for a value out of range or not finite.
  Status Check() const;
};

struct FrameCalibration {
  bool solved = false;
  std::string failure;  // why not, when !solved
  int tags_detected = 0;
  std::vector<TagObservation> tags;  // matched to the box (the bundle adjustment's input)
  std::vector<RejectedTag> rejected;
  Rigid3d cam_from_box_init;  // the per-view IPPE + LM pose (the planar start)
  Rigid3d cam_from_box;       // solved
  double init_rms_px = 0;
  double rms_px = 0;            // corner reprojection RMS after the bundle adjustment
  ViewUncertainty uncertainty;  // predicted by the covariance of the estimate
};

struct CameraCalibration {
  bool solved = false;
  std::string failure;
  std::string intrinsics_source;  // "nominal", "prior" or "views"
  CameraIntrinsics initial;       // before the bundle adjustment (Zhang's method when "views")
  CameraIntrinsics intrinsics;    // solved
  std::array<double, CameraIntrinsics::kNumParams> intrinsics_stddev{};
  Rigid3d cam_from_world;  // turntable mode
  PriorCheck prior_check;  // with fix_intrinsics and check_priors
};

struct CaptureCalibration {
  CalibrationMode mode = CalibrationMode::kTurntable;
  std::vector<CameraCalibration> cameras;
  std::vector<FrameCalibration> frames;  // in input order
  Rigid3d turntable_from_box;            // turntable mode
  double rms_px = 0;
  double residual_sigma_px = 0;
  int iterations = 0;
  bool converged = false;
  // The box: refined with the cameras (options.box_tolerance not zero), or
  // taken as given. box_as_built is the refined box, else the input's.
  bool box_refined = false;
  BoxTolerance box_tolerance;  // the refinement's, when box_refined
  CalibBox box_as_built;
  // The box check: the corner residuals' sigma (px) of the same views solved
  // with the box as given and with it refined (one of them is the solve
  // above, the other a second solve from its result); the tags' and faces'
  // moves are the refined solve's. NaN where the second solve failed.
  double sigma_box_as_given_px = NAN, sigma_box_refined_px = NAN;
  std::vector<TagRefinement> tag_moves;
  std::vector<FaceRefinement> face_moves;
  double detect_s = 0, init_s = 0, solve_s = 0, prior_check_s = 0;  // wall time of each step
};

// The ids of the tags the solved views used, ascending.
std::vector<int> TagsUsed(const CaptureCalibration& result);

// Tags of every frame, matched to the box, over `threads` threads; a frame
// with `observations` keeps them. A frame that cannot be read (core/image_file.h
// ReadImageFile: missing, not an image, or claiming more than kMaxImagePixels
// in its header) gives an empty observation with the reason, naming the file,
// in `failures` (same order as frames; empty string for success).
std::vector<ViewObservations> DetectFrames(const std::vector<CalibrationFrame>& frames,
                                           const CalibBox& box, const TagDetectorOptions& detector,
                                           int threads, std::vector<std::string>* failures);

// FailedPrecondition when nothing can be solved (no camera with usable views,
// no turntable axis in turntable mode: the message says what to try);
// InvalidArgument for bad options (CaptureCalibrationOptions::Check) or bad
// input (no frames, a frame of an unknown camera,
// fix_intrinsics without values, invalid nominal intrinsics, a prior for
// another image size, a NaN angle). A prior the views reject is not an
// error: CameraCalibration::prior_check says so and JudgeCalibration fails it.
Result<CaptureCalibration> CalibrateCapture(const CaptureCalibrationInput& input,
                                            const CaptureCalibrationOptions& options);

}  // namespace hairrig
