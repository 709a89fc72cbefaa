#include "reconstruction/skin_views.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/camera_model.h"
#include "core/image_file.h"
#include "reconstruction/hair_segmentation.h"

namespace hairrig {

bool FacingPixel(const ReconstructionView& view, double centre_depth_mm,
                 const Eigen::Vector3d& p_object, int cols, int rows, int* x, int* y) {
  const Eigen::Vector3d p_cam = view.cam_from_object * p_object;
  if (!(p_cam.z() < centre_depth_mm)) return false;
  Eigen::Vector2d uv;
  if (!ProjectChecked(view.camera, p_cam, &uv)) return false;
  const double u = std::round(uv.x()), v = std::round(uv.y());
  if (!(u >= 0 && v >= 0 && u < cols && v < rows)) return false;
  *x = static_cast<int>(u);
  *y = static_cast<int>(v);
  return true;
}

Status SkinViewOptions::Check() const {
  if (min_views < 1) return InvalidArgument("skin views: min_views must be at least 1");
  if (!(min_share > 0 && min_share <= 1))
    return InvalidArgument("skin views: min_share must lie in (0, 1]");
  return Status::Ok();
}

Result<SkinViews> SkinViews::FromLabels(const std::vector<ReconstructionView>& views,
                                        const std::vector<cv::Mat1b>& labels,
                                        const Eigen::Vector3d& head_centre_mm) {
  if (labels.size() != views.size()) {
    return InvalidArgument("skin views: " + std::to_string(labels.size()) + " labels for " +
                           std::to_string(views.size()) + " views");
  }
  SkinViews skin;
  for (size_t i = 0; i < views.size(); ++i) {
    const ReconstructionView& view = views[i];
    if (labels[i].cols != view.camera.width_px || labels[i].rows != view.camera.height_px) {
      ++skin.missing_;
      continue;
    }
    View v;
    v.view = view;
    v.centre_depth_mm = (view.cam_from_object * head_centre_mm).z();
    v.skin = labels[i] == kSegHead;
    skin.views_.push_back(std::move(v));
  }
  if (skin.views_.empty()) return NotFound("skin views: no view has a label of its camera's size");
  return skin;
}

Result<SkinViews> SkinViews::Load(const std::vector<ReconstructionView>& views,
                                  const std::string& masks_dir,
                                  const Eigen::Vector3d& head_centre_mm) {
  std::vector<cv::Mat1b> labels;
  for (const ReconstructionView& view : views) {
    const Result<cv::Mat> label =
        ReadImageFile(masks_dir + "/" + view.name + "_label.png", cv::IMREAD_GRAYSCALE);
    labels.push_back(label.ok() ? cv::Mat1b(*label) : cv::Mat1b());
  }
  Result<SkinViews> skin = FromLabels(views, labels, head_centre_mm);
  if (!skin.ok() && skin.status().code() == StatusCode::kNotFound) {
    return NotFound(masks_dir +
                    ": no view's label mask (<view>_label.png) could be read; run `hairrig "
                    "reconstruct DIR --stage points` first");
  }
  return skin;
}

bool SkinViews::OverSkin(const Eigen::Vector3d& p_object, const SkinViewOptions& o) const {
  int facing = 0, over_skin = 0;
  for (const View& v : views_) {
    int x = 0, y = 0;
    if (!FacingPixel(v.view, v.centre_depth_mm, p_object, v.skin.cols, v.skin.rows, &x, &y))
      continue;
    ++facing;
    over_skin += v.skin(y, x) != 0;
  }
  return over_skin >= o.min_views &&
         static_cast<double>(over_skin) >= o.min_share * static_cast<double>(facing);
}

}  // namespace hairrig
