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

#include <string>
#include <vector>

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

}  // namespace hairrig
