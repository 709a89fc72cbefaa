#include "reconstruction/free_space.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace hairrig {

Status FreeSpaceOptions::Check() const {
  if (!(margin_mm >= 0 && margin_mm <= 50))
    return InvalidArgument("free space margin_mm must lie in [0, 50]");
  if (min_views < 1) return InvalidArgument("free space min_views must be at least 1");
  if (cell_px < 1 || cell_px > 64) return InvalidArgument("free space cell_px must lie in [1, 64]");
  return Status::Ok();
}

namespace {

// The cell `p_cam` projects into; false behind the camera or outside the
// buffer (whose last row and column may reach a little past the image).
bool CellOf(const CameraIntrinsics& camera, const cv::Mat1f& buffer, int cell_px,
            const Eigen::Vector3d& p_cam, cv::Point* cell) {
  Eigen::Vector2d uv;
  if (!ProjectChecked(camera, p_cam, &uv)) return false;
  const double x = std::floor((uv.x() + 0.5) / cell_px), y = std::floor((uv.y() + 0.5) / cell_px);
  if (!(x >= 0 && y >= 0 && x < buffer.cols && y < buffer.rows)) return false;
  *cell = cv::Point(static_cast<int>(x), static_cast<int>(y));
  return true;
}

}  // namespace

FreeSpace::FreeSpace(const std::vector<ReconstructionView>& views,
                     const std::vector<OrientedPoint>& points, const FreeSpaceOptions& options)
    : options_(options) {
  const int cell = options.cell_px;
  views_.reserve(views.size());
  for (const ReconstructionView& view : views) {
    View v;
    v.camera = view.camera;
    v.cam_from_object = view.cam_from_object;
    v.nearest_mm =
        cv::Mat1f((view.camera.height_px + cell - 1) / cell,
                  (view.camera.width_px + cell - 1) / cell, std::numeric_limits<float>::infinity());
    views_.push_back(std::move(v));
  }
  for (const OrientedPoint& point : points) {
    const Eigen::Vector3d p = point.position_mm.cast<double>();
    for (const uint16_t index : point.views) {
      if (index >= views_.size()) continue;
      View& v = views_[index];
      const Eigen::Vector3d p_cam = v.cam_from_object * p;
      cv::Point c;
      if (!CellOf(v.camera, v.nearest_mm, cell, p_cam, &c)) continue;
      float& nearest = v.nearest_mm(c);
      nearest = std::min(nearest, static_cast<float>(p_cam.z()));
    }
  }
}

int FreeSpace::ViewsSeeingPast(const Eigen::Vector3d& p_object) const {
  int seeing = 0;
  for (const View& v : views_) {
    const Eigen::Vector3d p_cam = v.cam_from_object * p_object;
    cv::Point c;
    if (!CellOf(v.camera, v.nearest_mm, options_.cell_px, p_cam, &c)) continue;
    const float nearest = v.nearest_mm(c);
    seeing += std::isfinite(nearest) && p_cam.z() < nearest - options_.margin_mm;
  }
  return seeing;
}

}  // namespace hairrig
