// The calibration of a capture folder as `hairrig calibrate`, `capture
// --calibrate` and the batch's calibrate stage run it (the input from
// rig/capture_calibration_input.h, the solve from calibration/, the files
// and report written into <capture>/calibration/); the box refined from
// several captures (`hairrig calibrate-box`); and the calibration against the
// simulated rig's ground truth (`hairrig eval calibration`).
#pragma once

#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "calibration/calibration_evaluation.h"
#include "calibration/calibration_report.h"
#include "rig/capture_calibration_input.h"

namespace hairrig {

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
// <capture>/ground_truth/ (calibration/calibration_evaluation.h), in the frame
// of the true tags: the calibration's box (calibration/box_as_built.yaml when
// it refined the box, else the box file it was given, else the rig.yaml's)
// fitted to the box the simulated rig drew (ground_truth/box_as_built.yaml,
// checksummed; the rig.yaml's box for a ground truth without one). Errors: no
// calibration (run `hairrig calibrate`), no ground truth (not a simulated
// capture), a broken rig.yaml, a box file calibration.json names that is gone
// (FailedPrecondition naming it), a true box that fails its checksum, boxes
// with no tag in common, no solved view in the ground truth (named by the
// capture folder).
Result<CalibrationEvaluation> EvaluateCaptureCalibration(
    const CaptureCalibrationEvalOptions& options);

}  // namespace hairrig
