// Where the cameras see through: the space in front of the hair's seen
// surface. Each oriented point (point_cloud.h) lists the views that saw it
// (the stereo's views); nothing opaque lies between such a view's camera and
// the point, or the camera would not have seen it. A position that projects
// into a view in front of a point that view saw, by more than a margin, lies
// in the open air in that view's eyes: no hair can be there. Several views
// must agree (one view's stray point, or a point placed too deep by the
// stereo, does not carve the hair away).
//
// Strand growth uses it to keep a strand that winds on a curl's helix
// (helix_guide.h) from swinging out in front of the seen hair
// (strand_growth.h, StrandGrowthOptions::free_space).
//
// Frames and units as core/transform.h: mm in the views' object frame (the
// points' frame), pixel (0, 0) the centre of the top-left pixel. Each view
// keeps a depth buffer over cells of cell_px x cell_px pixels: the nearest
// depth (mm along the camera's optical axis) of the points it saw in that
// cell.
#pragma once

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/views.h"

namespace hairrig {

struct FreeSpaceOptions {
  // A position lies in front of a view's seen point when it is nearer that
  // camera by more than margin_mm (the stereo's depth error, a few mm at the
  // rig's distance, stays under it).
  double margin_mm = 3.0;
  // ... and it is free space when at least min_views views see it so. On
  // the simulated rig's 38 views a hair surface is seen by a dozen or more;
  // on the curls, 4 to 8 views carve the same share of strand samples
  // (docs/accuracy.md, "Curls kept out of the free space"), 8 shortens the
  // strands least.
  int min_views = 8;
  int cell_px = 4;  // the depth buffers' cell (px)

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

class FreeSpace {
 public:
  // The views' depth buffers from the points' view lists (indices into
  // `views`; an index past its end is ignored). Points behind a camera or
  // outside its buffer are left out of that view's buffer. `options` must
  // pass Check() (StrandGrowthOptions::Check checks them).
  FreeSpace(const std::vector<ReconstructionView>& views, const std::vector<OrientedPoint>& points,
            const FreeSpaceOptions& options);

  // How many views see a point of theirs more than margin_mm behind
  // `p_object` along its ray (the nearest cell is read).
  int ViewsSeeingPast(const Eigen::Vector3d& p_object) const;
  // True when ViewsSeeingPast reaches min_views.
  bool Free(const Eigen::Vector3d& p_object) const {
    return ViewsSeeingPast(p_object) >= options_.min_views;
  }

  const FreeSpaceOptions& options() const { return options_; }

 private:
  struct View {
    CameraIntrinsics camera;
    Rigid3d cam_from_object;
    cv::Mat1f nearest_mm;  // per cell; +inf where the view saw no point
  };
  std::vector<View> views_;
  FreeSpaceOptions options_;
};

}  // namespace hairrig
