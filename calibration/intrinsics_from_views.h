// A camera's intrinsics from its own views of the calibration box, with no
// starting guess: every box face seen with two or more tags in a view is a
// planar target, solved with the model and to the minimum of OpenCV's
// calibrateCamera (Zhang, "A flexible new technique for camera calibration",
// PAMI 2000; the closed-form start differs in its details): a homography per
// plane, the focal lengths in closed form from them with the principal point
// at the image centre (Sec. 3.1, zero skew), a pose per plane from its
// homography (Sec. 3.1), then Levenberg-Marquardt (Ceres) over pinhole +
// k1, k2, p1, p2 and every plane's pose, k3 held at 0 (Sec. 3.2-3.3).
// Fixed-size Eigen arithmetic and a Ceres ordering that does not depend on
// memory addresses, so the same views give the same bits in every run of the
// same binary on the same kind of CPU (calibrateCamera's results varied in
// the last digits with the process's memory layout);
// intrinsics_from_views_test.cpp compares the result with calibrateCamera's.
#pragma once

#include <opencv2/core/mat.hpp>
#include <vector>

#include "calibration/view_pose.h"
#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/status.h"

namespace hairrig {

// OpenCV's 3 x 3 camera matrix and distortion vector (k1 k2 p1 p2 [k3], CV_64F)
// as intrinsics; a missing k3 is 0.
CameraIntrinsics IntrinsicsFromOpenCv(const cv::Mat& camera_matrix, const cv::Mat& distortion,
                                      int width_px, int height_px);

struct IntrinsicsFromViews {
  CameraIntrinsics intrinsics;
  int planes = 0;     // (view, face) pairs used
  double rms_px = 0;  // corner reprojection RMS over the planes (px)
};

// `views` are one camera's matched observations. FailedPrecondition when fewer
// than `min_planes` (view, face) pairs have 2 or more tags (the message says
// how many were found and what to do); InvalidArgument for a bad image size.
Result<IntrinsicsFromViews> SolveIntrinsicsFromViews(
    const std::vector<const ViewObservations*>& views, const CalibBox& box, int width_px,
    int height_px, int min_planes = 4);

}  // namespace hairrig
