// The calibration's input from a capture folder (design.md section 4): the
// frames from manifest.json (view, stop, measured turntable angle, camera
// serial, file), the cameras and the `calibration` section of the rig config
// snapshot (<capture>/rig.yaml, relative paths against the folder of the
// config it was taken from):
//
//   calibration:
//     box: calib-box.yaml        # the box model (required)
//     box_height_mm: 600         # box origin above the turntable plate, along the axis
//     cameras:                   # optional nominal intrinsics by camera name;
//       upper: {fx_px: .., fy_px: .., cx_px: .., cy_px: .., k1: 0, ...}  # else from the views
#pragma once

#include <string>

#include "calibration/capture_calibration.h"

namespace hairrig {

// Errors name the file and field: a missing manifest or rig.yaml, a frame
// file outside the capture folder or missing, an unknown camera, a broken
// calibration section. Only frames whose checksum the manifest records are used.
Result<CaptureCalibrationInput> LoadCaptureCalibrationInput(const std::string& capture_dir);

}  // namespace hairrig
