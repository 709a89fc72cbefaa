// Where the cameras see bare skin: the head label of each view's segmentation
// (hair_segmentation.h, <masks_dir>/<view>_label.png, written by the points
// stage). A point of the object frame that a view faces and that projects
// onto that view's skin cannot be hair: hair there would hide the skin from
// that camera. Strand growth ends a strand where it runs in front of skin
// (strand_growth.h, through SkinGrid); the reconstruction's verdict counts
// strand samples over skin (reconstruction_verdict.h). Both use the same
// test, SkinViews::Count.
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
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"
#include "reconstruction/views.h"
#include "reconstruction/voxel_cache.h"

namespace hairrig {

class HeadModel;  // core/head_model.h

// Skin seen behind a point above the head's hairline and within this
// distance (mm) of the head is the scalp (SkinViews::ExcludeScalp).
inline constexpr double kScalpSkinBandMm = 12;

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

  // The views that face `p_object` (it lies nearer their camera than the
  // head's centre and projects inside the image; the nearest pixel is read)
  // and, of those, the ones that see skin there.
  void Count(const Eigen::Vector3d& p_object, int* facing, int* over_skin) const;
  // True when `p_object` is over skin by `options` (see SkinViewOptions).
  bool OverSkin(const Eigen::Vector3d& p_object, const SkinViewOptions& options) const;

  // From now on a point above `head`'s hairline and within `band_mm` of its
  // surface is over no skin (Count's over_skin 0): the skin seen behind it is
  // the scalp, which shows between the hair at a parting, a whorl or wherever
  // hair is thin, and hair there does not hide it. Without this, a strand
  // rooted where the scalp shows ends at its root. `head` (in the object
  // frame; it must outlive this) needs a scalp region (HeadSpec::scalp.defined,
  // else nothing is excluded); null or a band of 0 turns it off, the default.
  void ExcludeScalp(const HeadModel* head, double band_mm);
  // A copy whose skin masks are grown by `px` pixels (a (2 px + 1) square):
  // a point that projects within px of a view's skin counts as over it.
  SkinViews Grown(int px) const;

  int views_loaded() const { return static_cast<int>(views_.size()); }
  int views_missing() const { return missing_; }

 private:
  struct View {
    CameraIntrinsics camera;
    Rigid3d cam_from_object;
    double centre_depth_mm = 0;  // the head centre's depth in this camera
    cv::Mat1b skin;              // non-zero where the segmentation labels the head's skin
  };
  std::vector<View> views_;
  int missing_ = 0;
  const HeadModel* scalp_head_ = nullptr;
  double scalp_band_mm_ = 0;
  // Above scalp_head_'s hairline and within scalp_band_mm_ of it (ExcludeScalp).
  bool OverScalp(const Eigen::Vector3d& p_object) const;
};

// SkinViews::OverSkin answered once per cell of a regular grid, at the cell's
// centre (VoxelCache), for hot loops such as strand growth (a strand's every
// step). The grid spans origin_mm + [0, size) * cell_mm in the object frame;
// a point outside it is answered exactly. `views` must outlive the grid.
// Thread-safe.
class SkinGrid {
 public:
  SkinGrid(const SkinViews& views, const SkinViewOptions& options, const Eigen::Vector3f& origin_mm,
           const Eigen::Vector3i& size, double cell_mm);
  bool OverSkin(const Eigen::Vector3f& p_object) const { return cache_(p_object); }

 private:
  VoxelCache cache_;
};

}  // namespace hairrig
