#include "calibration/charuco_intrinsics.h"

#include <algorithm>
#include <cmath>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calibration/intrinsics_from_views.h"
#include "core/image_file.h"
#include "core/parallel.h"
#include "core/statistics.h"

namespace hairrig {
namespace {

cv::Ptr<cv::aruco::CharucoBoard> OpenCvBoard(const ChArUcoBoard& board) {
  return cv::aruco::CharucoBoard::create(
      board.squares_x, board.squares_y, static_cast<float>(board.square_mm),
      static_cast<float>(board.marker_mm),
      cv::aruco::getPredefinedDictionary(board.opencv_dictionary));
}

struct Solve {
  cv::Mat camera_matrix, distortion, stddev;
  std::vector<double> image_rms;
  double rms = 0;
};

// calibrateCamera over the images in `use` (indices into corners).
Solve SolveOnce(const std::vector<ChArUcoCorners>& corners, const std::vector<size_t>& use,
                const ChArUcoBoard& board, cv::Size size, bool fix_k3) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (size_t i : use) {
    std::vector<cv::Point3f> o;
    std::vector<cv::Point2f> p;
    for (size_t k = 0; k < corners[i].ids.size(); ++k) {
      const Eigen::Vector3d& b = board.corners_board_mm[static_cast<size_t>(corners[i].ids[k])];
      o.emplace_back(static_cast<float>(b.x()), static_cast<float>(b.y()),
                     static_cast<float>(b.z()));
      p.emplace_back(static_cast<float>(corners[i].corners_px[k].x()),
                     static_cast<float>(corners[i].corners_px[k].y()));
    }
    object.push_back(std::move(o));
    image.push_back(std::move(p));
  }
  Solve s;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat stddev_extrinsics, per_view;
  s.rms = cv::calibrateCamera(
      object, image, size, s.camera_matrix, s.distortion, rvecs, tvecs, s.stddev, stddev_extrinsics,
      per_view, fix_k3 ? cv::CALIB_FIX_K3 : 0,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  for (int i = 0; i < per_view.rows; ++i) s.image_rms.push_back(per_view.at<double>(i));
  return s;
}

std::string FailureSummary(const std::vector<ChArUcoImage>& images) {
  std::string text;
  int listed = 0;
  for (const ChArUcoImage& image : images) {
    if (image.used || image.failure.empty()) continue;
    if (listed++ < 5) text += "\n  " + image.path + ": " + image.failure;
  }
  if (listed > 5) text += "\n  ... and " + std::to_string(listed - 5) + " more";
  return text;
}

}  // namespace

ChArUcoCorners DetectChArUcoCorners(const cv::Mat& image, const ChArUcoBoard& board) {
  ChArUcoCorners out;
  if (image.empty()) return out;
  cv::Mat gray = image;
  if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  const cv::Ptr<cv::aruco::CharucoBoard> cv_board = OpenCvBoard(board);
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(gray, cv_board->dictionary, marker_corners, marker_ids);
  out.markers = static_cast<int>(marker_ids.size());
  if (marker_ids.empty()) return out;
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, gray, cv_board, corners, ids);
  if (ids.empty()) return out;
  // OpenCV 4.6 returns the interpolated corners half a pixel off (measured
  // against rendered ground truth: +0.50, +0.51 px) and barely refined, so
  // every corner is refined here. The window must stay clear of the markers,
  // whose borders are (square - marker) / 2 from the corner along each axis.
  double square_px = 0;
  for (const auto& m : marker_corners) square_px += 0.25 * cv::arcLength(m, true);
  square_px *= board.square_mm / board.marker_mm / static_cast<double>(marker_corners.size());
  const double gap_px = square_px * (board.square_mm - board.marker_mm) / (2 * board.square_mm);
  const int half_window = std::clamp(static_cast<int>(0.7 * gap_px), 2, 15);
  cv::cornerSubPix(gray, corners, cv::Size(half_window, half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 1e-3));
  for (size_t k = 0; k < ids.size(); ++k) {
    out.ids.push_back(ids[k]);
    out.corners_px.emplace_back(corners[k].x, corners[k].y);
  }
  return out;
}

Status ChArUcoCalibrationOptions::Check() const {
  if (min_corners < 4)
    return InvalidArgument("min_corners must be at least 4, got " + std::to_string(min_corners));
  if (min_images < 1)
    return InvalidArgument("min_images must be at least 1, got " + std::to_string(min_images));
  if (threads < 1)
    return InvalidArgument("threads must be at least 1, got " + std::to_string(threads));
  return Status::Ok();
}

Result<ChArUcoCalibration> CalibrateIntrinsicsFromChArUco(
    const std::vector<std::string>& image_paths, const ChArUcoBoard& board,
    const ChArUcoCalibrationOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("calibrate-intrinsics"));
  if (image_paths.empty()) return InvalidArgument("calibrate-intrinsics: no images given");
  ChArUcoCalibration out;
  out.images.resize(image_paths.size());
  std::vector<ChArUcoCorners> corners(image_paths.size());
  std::vector<cv::Size> sizes(image_paths.size());
  ParallelFor(image_paths.size(), options.threads, [&] {
    return [&](size_t i) {
      out.images[i].path = image_paths[i];
      const Result<cv::Mat> read = ReadImageFile(image_paths[i], cv::IMREAD_GRAYSCALE);
      if (!read.ok()) {
        out.images[i].failure = "cannot be read (" + read.status().message() + ")";
        return;
      }
      const cv::Mat& image = *read;
      sizes[i] = image.size();
      corners[i] = DetectChArUcoCorners(image, board);
      out.images[i].detected = corners[i];
      out.images[i].markers = corners[i].markers;
      out.images[i].corners = static_cast<int>(corners[i].ids.size());
      if (out.images[i].corners < options.min_corners)
        out.images[i].failure = std::to_string(out.images[i].corners) +
                                " chessboard corners found (" + std::to_string(corners[i].markers) +
                                " markers), " + std::to_string(options.min_corners) + " needed";
    };
  });
  std::vector<size_t> use;
  cv::Size size;
  for (size_t i = 0; i < image_paths.size(); ++i) {
    if (!out.images[i].failure.empty()) continue;
    if (size.empty()) size = sizes[i];
    if (sizes[i] != size)
      return FailedPrecondition("calibrate-intrinsics: " + image_paths[i] + " is " +
                                std::to_string(sizes[i].width) + " x " +
                                std::to_string(sizes[i].height) + " px, the images before it " +
                                std::to_string(size.width) + " x " + std::to_string(size.height) +
                                "; record every image at the camera's capture resolution");
    use.push_back(i);
  }
  const auto too_few = [&] {
    return FailedPrecondition(
        "calibrate-intrinsics: " + std::to_string(use.size()) + " of " +
        std::to_string(image_paths.size()) + " images show the board (" +
        std::to_string(options.min_images) +
        " needed); record more images with the whole board in view, tilted, in every part of "
        "the image" +
        FailureSummary(out.images));
  };
  if (static_cast<int>(use.size()) < options.min_images) return too_few();
  Solve solve = SolveOnce(corners, use, board, size, options.fix_k3);
  // Leave out images that disagree (a blurred or bent board), then solve again.
  const double limit = std::max(3.0 * Median(solve.image_rms), 1.0);
  std::vector<size_t> kept;
  for (size_t k = 0; k < use.size(); ++k) {
    if (solve.image_rms[k] <= limit) {
      kept.push_back(use[k]);
    } else {
      out.images[use[k]].failure = "reprojection RMS " + std::to_string(solve.image_rms[k]) +
                                   " px is above " + std::to_string(limit) +
                                   " px (a moving or bent board?)";
    }
  }
  if (kept.size() != use.size()) {
    use = kept;
    if (static_cast<int>(use.size()) < options.min_images) return too_few();
    solve = SolveOnce(corners, use, board, size, options.fix_k3);
  }
  out.intrinsics =
      IntrinsicsFromOpenCv(solve.camera_matrix, solve.distortion, size.width, size.height);
  HR_RETURN_IF_ERROR(
      out.intrinsics.Check().WithContext("calibrate-intrinsics: the solution is not usable"));
  for (int p = 0; p < CameraIntrinsics::kNumParams && p < solve.stddev.rows; ++p)
    out.stddev[static_cast<size_t>(p)] = solve.stddev.at<double>(p);
  if (options.fix_k3) out.stddev[8] = 0;
  out.rms_px = solve.rms;
  out.images_used = static_cast<int>(use.size());
  for (size_t k = 0; k < use.size(); ++k) {
    out.images[use[k]].used = true;
    out.images[use[k]].rms_px = solve.image_rms[k];
  }
  return out;
}

}  // namespace hairrig
