#include "reconstruction/skin_views.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/camera_model.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "reconstruction/hair_segmentation.h"

namespace hairrig {

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
    v.camera = view.camera;
    v.cam_from_object = view.cam_from_object;
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

void SkinViews::ExcludeScalp(const HeadModel* head, double band_mm) {
  const bool scalp = head != nullptr && head->head().scalp.defined && band_mm > 0;
  scalp_head_ = scalp ? head : nullptr;
  scalp_band_mm_ = scalp ? band_mm : 0;
}

SkinViews SkinViews::Grown(int px) const {
  SkinViews grown = *this;
  if (px <= 0) return grown;
  const cv::Mat kernel =
      cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * px + 1, 2 * px + 1));
  for (View& v : grown.views_) {
    cv::Mat1b dilated;
    cv::dilate(v.skin, dilated, kernel);
    v.skin = dilated;
  }
  return grown;
}

bool SkinViews::OverScalp(const Eigen::Vector3d& p_object) const {
  return scalp_head_ != nullptr && scalp_head_->AboveHairline(p_object) &&
         scalp_head_->SignedDistance(p_object, nullptr) < scalp_band_mm_;
}

void SkinViews::Count(const Eigen::Vector3d& p_object, int* facing, int* over_skin) const {
  *facing = 0;
  *over_skin = 0;
  const bool scalp = OverScalp(p_object);
  for (const View& v : views_) {
    const Eigen::Vector3d p_cam = v.cam_from_object * p_object;
    if (!(p_cam.z() < v.centre_depth_mm)) continue;
    Eigen::Vector2d uv;
    if (!ProjectChecked(v.camera, p_cam, &uv)) continue;
    const double x = std::round(uv.x()), y = std::round(uv.y());
    if (!(x >= 0 && y >= 0 && x < v.skin.cols && y < v.skin.rows)) continue;
    ++*facing;
    *over_skin += !scalp && v.skin(static_cast<int>(y), static_cast<int>(x)) != 0;
  }
}

bool SkinViews::OverSkin(const Eigen::Vector3d& p_object, const SkinViewOptions& o) const {
  int facing = 0, over_skin = 0;
  Count(p_object, &facing, &over_skin);
  return over_skin >= o.min_views &&
         static_cast<double>(over_skin) >= o.min_share * static_cast<double>(facing);
}

SkinGrid::SkinGrid(const SkinViews& views, const SkinViewOptions& options,
                   const Eigen::Vector3f& origin_mm, const Eigen::Vector3i& size, double cell_mm)
    : cache_([&views, options](
                 const Eigen::Vector3f& p) { return views.OverSkin(p.cast<double>(), options); },
             origin_mm, size, cell_mm) {}

}  // namespace hairrig
