// One camera's intrinsics from images of a ChArUco board:
// `hairrig calibrate-intrinsics`, for the technician who recalibrates a camera
// alone. The result can be held fixed in the box calibration
// (`hairrig calibrate --intrinsics`), where the principal point is otherwise
// weakly observed.
//
// Per image: ArUco markers found (OpenCV contrib, 4.6 API), the chessboard
// corners between them interpolated and refined to subpixel. Then OpenCV's
// calibrateCamera (Zhang's initialisation, Levenberg-Marquardt) over all
// usable images; an image whose RMS exceeds max(3 x median, 1 px) is left out
// and the solve repeated once. Pixels in the OpenCV convention, board frame
// in mm (core/charuco_board.h).
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/charuco_board.h"
#include "core/status.h"

namespace hairrig {

struct ChArUcoCorners {
  int markers = 0;                          // ArUco markers found
  std::vector<int> ids;                     // chessboard corner ids (core/charuco_board.h)
  std::vector<Eigen::Vector2d> corners_px;  // same order
};

// Never fails: an image without the board gives no corners. `image` is
// 8-bit grey or BGR.
ChArUcoCorners DetectChArUcoCorners(const cv::Mat& image, const ChArUcoBoard& board);

struct ChArUcoCalibrationOptions {
  bool fix_k3 = true;    // k3 is rarely observable on low-distortion lenses
  int min_corners = 12;  // per image, at least 4
  int min_images = 6;    // at least 1
  int threads = 2;       // detection, at least 1

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct ChArUcoImage {
  std::string path;
  bool used = false;
  std::string failure;  // why not, when !used
  int markers = 0, corners = 0;
  double rms_px = 0;  // reprojection RMS of its corners after the solve
  ChArUcoCorners detected;
};

struct ChArUcoCalibration {
  CameraIntrinsics intrinsics;
  std::array<double, CameraIntrinsics::kNumParams>
      stddev{};  // kParamNames order; 0 for held parameters
  double rms_px = 0;
  int images_used = 0;
  std::vector<ChArUcoImage> images;  // input order
};

// InvalidArgument for no paths or bad options (ChArUcoCalibrationOptions::Check,
// the field named); FailedPrecondition when fewer than
// `min_images` images show the board well enough (the message says how many
// did and why the others failed, and what to record instead) or when the
// images disagree on their size; the rest of the failures are per image (one
// that cannot be read gives core/image_file.h ReadImageFile's reason).
Result<ChArUcoCalibration> CalibrateIntrinsicsFromChArUco(
    const std::vector<std::string>& image_paths, const ChArUcoBoard& board,
    const ChArUcoCalibrationOptions& options = {});

}  // namespace hairrig
