// The calibration's input from a capture folder (docs/design.md section 4): the
// frames from manifest.json (view, stop, measured turntable angle, camera
// serial, file), the cameras and the `calibration` section of the rig config
// snapshot (<capture>/rig.yaml, relative paths against the folder of the
// config it was taken from):
//
//   calibration:
//     box: calib-box.yaml        # the box model (required)
//     box_height_mm: 600         # box origin above the turntable plate, along the axis
//     box_yaw_deg: 10            # the box's turn about the axis from the turntable's x axis
//     (default 0) cameras:                   # optional nominal intrinsics by camera name;
//       upper: {fx_px: .., fy_px: .., cx_px: .., cy_px: .., k1: 0, ...}  # else from the views
#pragma once

#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "calibration/calibration_evaluation.h"
#include "calibration/calibration_report.h"
#include "calibration/capture_calibration.h"
#include "rig/rig_config.h"

namespace hairrig {

// A capture's rig.yaml snapshot, paths relative to the config it was taken
// from; sections no registered rig extension reads are ignored (the simulated
// rig's `sim` where it is not registered).
Result<RigConfig> LoadCaptureRigConfig(const std::string& capture_dir);

// A rig config's `calibration` section: the box model and where it hangs in the turntable frame.
struct CalibrationSection {
  CalibBox box;
  std::string box_file;  // where the box came from
  double box_height_mm = 0;
  double box_yaw_deg = 0;
};
// Errors name the file, line and field.
Result<CalibrationSection> ReadCalibrationSection(const RigConfig& config);
// The calibration section checked as ReadCalibrationSection reads it (its
// keys, numbers and box file), when the config has one; Ok without one.
// Capture and `devices` check it, so a mistake shows before any frame.
Status CheckCalibrationSection(const RigConfig& config);

// The frames are read and checked by rig/manifest_frames.h: a frame file that
// does not verify against the size and SHA-256 the manifest records (missing,
// changed, or leading outside the capture folder) is marked unusable with the
// reason. Each camera's image size is read from its first usable frame's
// header, nothing decoded (core/image_file.h; a frame whose header is
// unreadable or claims more than kMaxImagePixels is skipped, and the
// calibration names it). Errors name the file and field: a missing manifest
// or rig.yaml, a damaged manifest frame entry, two entries with the same
// SHA-256, an unknown camera (the entry's serial field, and what to do), a
// frames/ folder leading outside the capture folder, a broken calibration
// section.
Result<CaptureCalibrationInput> LoadCaptureCalibrationInput(const std::string& capture_dir);

// Holds every camera at the intrinsics the files give for its serial
// (files from `calibrate-intrinsics` or calibration.json; a later file wins
// for a serial given twice), with their standard deviations. InvalidArgument
// names a camera no file gives, or one calibrated at another image size.
Status ApplyIntrinsicsPriors(const std::vector<std::string>& prior_files,
                             CaptureCalibrationInput* input);

struct CalibrateFolderOptions {
  CaptureCalibrationOptions calibration;
  std::vector<std::string> prior_files;  // non-empty: intrinsics held (ApplyIntrinsicsPriors)
  // Non-empty: the box to solve against (core/calib_box.h: drawn, or a
  // box_as_built.yaml), in place of the rig config's calibration.box.
  std::string box_file;
  // Tags already detected (TagDetectionSink::WaitForAll), by DetectionKey of the frame path.
  const std::map<std::string, ViewObservations>* detected = nullptr;
  std::function<void()> on_written;  // called once calibration.json and the exports are written

  // InvalidArgument naming the field: calibration.* (CaptureCalibrationOptions::Check),
  // an empty prior_files entry.
  Status Check() const;
};

struct CalibratedFolder {
  std::string out_dir;  // <capture>/calibration
  CaptureCalibrationInput input;
  CaptureCalibration result;
  CalibrationVerdict verdict;
  double write_s = 0;   // writing calibration.json and the exports
  double report_s = 0;  // writing the report

  // `hairrig calibrate`'s summary: verdict and reasons, views solved, RMS,
  // timings, each held prior's check against the views, the report's path.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// `hairrig calibrate`: loads the capture, solves it and writes
// <capture>/calibration/ with its report. InvalidArgument for bad options
// (CalibrateFolderOptions::Check).
Result<CalibratedFolder> CalibrateCaptureFolder(const std::string& capture_dir,
                                                const CalibrateFolderOptions& options);

struct RefineBoxOptions {
  // Captures of one box, solved in this order; each starts from the box the
  // one before refined, held by that box's standard deviations.
  std::vector<std::string> capture_dirs;
  std::string box_file;  // where to start; empty: the first capture's rig config's box
  std::vector<std::string> prior_files;  // intrinsics held, as CalibrateFolderOptions'
  std::string out_file;                  // the box as built (core/calib_box.h format)
  CaptureCalibrationOptions calibration;

  // InvalidArgument naming the field: no capture, no out_file, an empty prior
  // file, calibration.* (a box_tolerance of zero refines nothing).
  Status Check() const;
};

struct RefinedBox {
  struct Step {
    std::string capture_dir;
    int views = 0, views_solved = 0;
    double sigma_as_given_px = 0, sigma_refined_px = 0;
    double largest_tag_move_mm = 0;  // from the box this step started from
    double largest_tag_sd_mm = 0;    // of the refined box's observed tags
    std::string verdict;
  };
  std::string out_file;
  std::vector<Step> steps;
  CalibBox box;

  // `hairrig calibrate-box`'s summary: the file written and one line per capture.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// `hairrig calibrate-box`: the box as built refined from several captures in
// turn (the captures' own calibration/ folders are left as they are), written
// to out_file with its standard deviations. Errors: bad options, a capture
// that cannot be loaded or solved (named), a file that cannot be written.
Result<RefinedBox> RefineBoxFromCaptures(const RefineBoxOptions& options);

struct CaptureCalibrationEvalOptions {
  std::string capture_dir;  // a calibrated capture of the simulated rig

  Status Check() const;  // InvalidArgument naming the field
};

// `hairrig eval calibration`: <capture>/calibration/calibration.json against
// <capture>/ground_truth/ (calibration/calibration_evaluation.h), with the box
// of the capture's rig.yaml. Errors: no calibration (run `hairrig calibrate`),
// no ground truth (not a simulated capture), a broken rig.yaml, no solved view
// in the ground truth (named by the capture folder).
Result<CalibrationEvaluation> EvaluateCaptureCalibration(
    const CaptureCalibrationEvalOptions& options);

}  // namespace hairrig
