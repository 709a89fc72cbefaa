#include "calibration/intrinsics_from_views.h"

#include <map>

#include <opencv2/calib3d.hpp>

namespace hairrig {

namespace {

// The tags of one view grouped by face, as planar point sets in the face frame (z = 0).
void AddFacePlanes(const ViewObservations& view, const CalibBox& box,
                   std::vector<std::vector<cv::Point3f>>* object, std::vector<std::vector<cv::Point2f>>* image) {
  std::map<int, std::vector<const TagObservation*>> by_face;
  for (const TagObservation& tag : view.tags) {
    const BoxTag* model = box.FindTag(tag.id);
    if (model) by_face[model->face].push_back(&tag);
  }
  for (const auto& [face_index, tags] : by_face) {
    if (tags.size() < 2) continue;  // one square leaves the focal length ambiguous
    const BoxFace& face = box.faces[static_cast<size_t>(face_index)];
    std::vector<cv::Point3f> plane_points;
    std::vector<cv::Point2f> pixels;
    for (const TagObservation* tag : tags) {
      for (size_t k = 0; k < 4; ++k) {
        const Eigen::Vector3d rel = tag->corners_box_mm[k] - face.center_box_mm;
        plane_points.emplace_back(static_cast<float>(rel.dot(face.right_box)), static_cast<float>(rel.dot(face.down_box)), 0.f);
        pixels.emplace_back(static_cast<float>(tag->corners_px[k].x()), static_cast<float>(tag->corners_px[k].y()));
      }
    }
    object->push_back(std::move(plane_points));
    image->push_back(std::move(pixels));
  }
}

}  // namespace

CameraIntrinsics IntrinsicsFromOpenCv(const cv::Mat& camera_matrix, const cv::Mat& distortion, int width_px,
                                      int height_px) {
  const auto d = [&](int i) { return i < static_cast<int>(distortion.total()) ? distortion.at<double>(i) : 0.0; };
  const double params[CameraIntrinsics::kNumParams] = {
      camera_matrix.at<double>(0, 0), camera_matrix.at<double>(1, 1), camera_matrix.at<double>(0, 2),
      camera_matrix.at<double>(1, 2), d(0), d(1), d(2), d(3), d(4)};
  return CameraIntrinsics::FromParams(params, width_px, height_px);
}

Result<IntrinsicsFromViews> SolveIntrinsicsFromViews(const std::vector<const ViewObservations*>& views,
                                                     const CalibBox& box, int width_px, int height_px,
                                                     int min_planes) {
  if (width_px <= 0 || height_px <= 0)
    return InvalidArgument("intrinsics from views: image size " + std::to_string(width_px) + " x " +
                           std::to_string(height_px) + " is not positive");
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const ViewObservations* view : views) AddFacePlanes(*view, box, &object, &image);
  if (static_cast<int>(object.size()) < min_planes) {
    return FailedPrecondition("intrinsics from views: " + std::to_string(object.size()) +
                              " box face(s) seen with 2 or more tags, " + std::to_string(min_planes) +
                              " needed; give nominal intrinsics in the rig config (calibration.cameras) or a "
                              "prior from calibrate-intrinsics");
  }
  cv::Mat camera_matrix, distortion;
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = cv::CALIB_FIX_K3;
  IntrinsicsFromViews out;
  out.rms_px = cv::calibrateCamera(object, image, cv::Size(width_px, height_px), camera_matrix, distortion, rvecs,
                                   tvecs, flags);
  out.intrinsics = IntrinsicsFromOpenCv(camera_matrix, distortion, width_px, height_px);
  out.planes = static_cast<int>(object.size());
  const Status valid = out.intrinsics.Validate();
  if (!valid.ok()) return FailedPrecondition("intrinsics from views: the solution is not usable: " + valid.message());
  return out;
}

}  // namespace hairrig
