// AprilTag 36h11 detection with libapriltag, corners in the project's pixel
// convention (core/transform.h: the centre of pixel (0,0) is at (0,0)).
//
// Debian's libapriltag 3.3 reports corners with the centre of pixel (0,0) at
// (0.5, 0.5); kApriltagToOpenCvOffsetPx converts, here and nowhere else. The
// rendered-view test in tests/ proves the correction against ground truth.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/status.h"

namespace hairrig {

inline constexpr double kApriltagToOpenCvOffsetPx = -0.5;

struct TagDetection {
  int id = -1;
  // libapriltag order (core/calib_box.h kTagCornerSigns), OpenCV pixel convention.
  std::array<Eigen::Vector2d, 4> corners_px;
  int hamming = 0;             // bits corrected while decoding
  double decision_margin = 0;  // decoder confidence; higher is better
};

struct TagDetectorOptions {
  // Image decimation for quad finding; 0 chooses from the image size (1 up to
  // 1000 px on the long side, 2 up to 3000, else 3). Corners are refined at
  // full resolution either way.
  double decimate = 0;
  int threads = 1;
  int max_hamming = 1;  // detections with more corrected bits are dropped
  // With `subtract_half_pixel` false, corners are returned as libapriltag
  // gives them (for measuring the convention offset only).
  bool subtract_half_pixel = true;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

class TagDetector {
 public:
  // InvalidArgument naming the field of bad options (TagDetectorOptions::Check).
  static Result<std::unique_ptr<TagDetector>> Create(const TagDetectorOptions& options);
  ~TagDetector();
  // Accepts CV_8UC1 or CV_8UC3 (BGR). InvalidArgument for other types or an empty image.
  Result<std::vector<TagDetection>> Detect(const cv::Mat& image);

 private:
  struct Impl;
  explicit TagDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
