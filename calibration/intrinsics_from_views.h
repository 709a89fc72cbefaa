// A camera's intrinsics from its own views of the calibration box, with no
// starting guess: every box face seen with two or more tags
// in a view is a planar target, and OpenCV's calibrateCamera (Zhang's method,
// then Levenberg-Marquardt) solves pinhole + k1, k2, p1, p2 from them, k3
// held at 0. This is also the OpenCV-only baseline's intrinsics.
#pragma once

#include <vector>

#include <opencv2/core/mat.hpp>

#include "calibration/view_pose.h"
#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/status.h"

namespace hairrig {

// OpenCV's 3 x 3 camera matrix and distortion vector (k1 k2 p1 p2 [k3], CV_64F)
// as intrinsics; a missing k3 is 0.
CameraIntrinsics IntrinsicsFromOpenCv(const cv::Mat& camera_matrix, const cv::Mat& distortion, int width_px,
                                      int height_px);

struct IntrinsicsFromViews {
  CameraIntrinsics intrinsics;
  int planes = 0;       // (view, face) pairs used
  double rms_px = 0;    // calibrateCamera's reprojection RMS
};

// `views` are one camera's matched observations. FailedPrecondition when fewer
// than `min_planes` (view, face) pairs have 2 or more tags (the message says
// how many were found and what to do); InvalidArgument for a bad image size.
Result<IntrinsicsFromViews> SolveIntrinsicsFromViews(const std::vector<const ViewObservations*>& views,
                                                     const CalibBox& box, int width_px, int height_px,
                                                     int min_planes = 4);

}  // namespace hairrig
