// Where the cameras see bare skin: the head label of each view's segmentation
// (hair_segmentation.h, <masks_dir>/<view>_label.png, written by the points
// stage). A point of the object frame that a view faces and that projects
// onto that view's skin cannot be hair: hair there would hide the skin from
// that camera. Strand growth ends a strand where it runs in front of skin
// (strand_growth.h); the reconstruction's verdict counts strand samples over
// skin (reconstruction_verdict.h). Both use the same test, FacingPixel.
//
// "Facing" is judged against the head's centre: the point lies nearer the
// camera than the centre does, so the head does not hide it from the view
// (a point on the far side of the head projects onto skin that stands in
// front of it, which says nothing about the point).
//
// Frames and units as core/transform.h: mm in the views' object frame, pixel
// (0, 0) the centre of the top-left pixel; the nearest pixel is read.
#pragma once

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/status.h"
#include "reconstruction/views.h"

namespace hairrig {

// The pixel (x, y) of `p_object` in `view` when the view faces it (nearer the
// camera than `centre_depth_mm`, the head centre's depth in that camera) and
// it falls inside a cols x rows image; false otherwise.
bool FacingPixel(const ReconstructionView& view, double centre_depth_mm,
                 const Eigen::Vector3d& p_object, int cols, int rows, int* x, int* y);

struct SkinViewOptions {
  // A point is over skin when at least min_views of the views facing it see
  // skin there, and they are at least min_share of those views (one view's
  // segmentation error, or calibration error at the hairline, does not end a
  // strand). A view that faces a point can still see it from the side, past
  // the head's outline, so a quarter suffices: on the bangs a half left 5.6 %
  // of the strand samples over skin, a quarter 1.9 % (docs/accuracy.md,
  // "Strands in front of skin").
  int min_views = 2;
  double min_share = 0.25;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

class SkinViews {
 public:
  // Reads each view's label mask from masks_dir; a view whose label cannot
  // be read, or whose size differs from its camera's, is left out (counted in
  // views_missing()). NotFound when no view's label could be read, naming the
  // folder (run the points stage first).
  static Result<SkinViews> Load(const std::vector<ReconstructionView>& views,
                                const std::string& masks_dir,
                                const Eigen::Vector3d& head_centre_mm);
  // The same from labels in memory, labels[i] for views[i] (SegmentLabel
  // values; an empty one leaves its view out). InvalidArgument when the
  // counts differ; NotFound when no label is left.
  static Result<SkinViews> FromLabels(const std::vector<ReconstructionView>& views,
                                      const std::vector<cv::Mat1b>& labels,
                                      const Eigen::Vector3d& head_centre_mm);

  // True when `p_object` is over skin by `options` (see SkinViewOptions).
  bool OverSkin(const Eigen::Vector3d& p_object, const SkinViewOptions& options) const;

  int views_loaded() const { return static_cast<int>(views_.size()); }
  int views_missing() const { return missing_; }

 private:
  struct View {
    ReconstructionView view;
    double centre_depth_mm = 0;
    cv::Mat1b skin;  // non-zero where the segmentation labels the head's skin
  };
  std::vector<View> views_;
  int missing_ = 0;
};

}  // namespace hairrig
