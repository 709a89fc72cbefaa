// `hairrig calibrate-intrinsics`: one camera's intrinsics from a folder of its
// images of a ChArUco board (calibration/charuco_intrinsics.h), written as a
// file `hairrig calibrate --intrinsics` holds fixed (calibration/calibration_io.h
// WriteIntrinsicsFile), and optionally the corners as mrcal's corners cache.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "calibration/charuco_intrinsics.h"
#include "core/status.h"

namespace hairrig {

struct IntrinsicsFolderOptions {
  // The camera's images of the board, taken by name order: every .png, .jpg,
  // .jpeg, .tif and .tiff file (any case) directly in the folder.
  std::string images_dir;
  std::string board_file;          // the board (core/charuco_board.h LoadChArUcoBoard)
  std::string serial;              // the camera's serial, as in the rig config
  std::string out_file;            // empty: <images_dir>/intrinsics.json
  std::string mrcal_corners_file;  // non-empty: the corners for mrcal too (WriteMrcalCorners)
  ChArUcoCalibrationOptions calibration;

  // InvalidArgument naming the field: a missing folder, board or serial,
  // calibration.* (ChArUcoCalibrationOptions::Check).
  Status Check() const;
};

struct IntrinsicsFolderSummary {
  std::string out_file;
  std::string serial;
  int images = 0;  // in the folder
  ChArUcoCalibration result;

  // out, serial, images, images_used, rms_px, intrinsics, intrinsics_stddev
  // (by parameter name) and left_out ("<image>: <why>" per image not used).
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: the board file (named), a folder without images, the calibration's
// (too few usable images, named), a file that cannot be written (named).
Result<IntrinsicsFolderSummary> CalibrateIntrinsicsFolder(const IntrinsicsFolderOptions& options);

}  // namespace hairrig
