// Line-based multi-view stereo on hair pixels: per reference pixel a 3D line
// segment (depth and 3D direction) by PatchMatch, after Nam et al. 2019
// ("Strand-accurate multi-view hair capture", CVPR): a hypothesis is scored by
// how its projection into neighbouring views follows their 2D orientation
// maps. This takes the place of Luo 2013 Sec. 4's PMVS.
//
// Parametrisation: the segment passes through the reference pixel's ray at
// depth z (mm along the optical axis), and its projection in the reference
// view follows the reference orientation map (as Nam et al.), so one angle is
// left: the tilt phi out of the image plane, in (-max_tilt, max_tilt). Where
// Nam et al.'s segment is straight along the pixel's orientation, here its
// samples by default follow the map's streamline through the pixel
// (LineMvsOptions::follow_orientation), so that it bends with a curl. The
// search is PatchMatch (Barnes et al. 2009; Bleyer et al. 2011): random
// hypotheses in the depth range, propagation from the scan's previous
// neighbours in alternating directions, and random refinement with a range
// that halves every iteration.
//
// Costs (0 best .. 1 worst), per neighbour view, averaged over samples along
// the segment; a view's cost is the mean of the best `views_in_cost`:
//   orientation: min(|angle difference|, truncation) / truncation between the
//                segment's projected direction and the neighbour's map, 1 off
//                the neighbour's hair mask;
//   photometric: (1 - NCC) / 2 of grey values on a strip along the segment
//                (the baseline: the same search with no orientation term);
//   both:        their mean (the default: a segment can tilt to follow one
//                neighbour's orientation at any depth, so orientation alone
//                pins depth weakly; measured in line_mvs_test.cpp).
//
// Frames: depth maps are per reference view in its camera frame; directions
// are returned in the object frame. Units mm, px, deg.
#pragma once

#include <functional>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

enum class MvsCost { kOrientation, kPhotometric, kBoth };

struct LineMvsOptions {
  MvsCost cost = MvsCost::kBoth;
  int stride_px = 3;             // reference pixels on a grid of this step (1 = every pixel)
  int neighbours = 4;            // views compared with each reference view
  int views_in_cost = 2;         // ... of which the best this many score a hypothesis
  double min_baseline_deg = 8;   // neighbour views are at least this far in viewing direction ...
  double max_baseline_deg = 50;  // ... and at most this far
  int iterations = 4;            // with the hull's prior 4 find the depth 6 do (docs/accuracy.md)
  int samples = 7;               // along the segment (odd)
  double sample_step_px = 2.0;   // their spacing, as seen in the reference view
  // The samples follow the streamline of the reference view's orientation map
  // through the pixel, so that a hypothesis bends with a curl in the image
  // (its tilt sets how its depth changes along it); false: a straight
  // segment along the pixel's orientation, as Nam et al.
  bool follow_orientation = true;
  double orientation_truncation_deg = 25;
  double max_tilt_deg = 75;
  double depth_margin_mm =
      200;  // without a prior: hypotheses within this of the subject's centre depth
  // With a prior depth (MvsView::prior_depth_mm, the visual hull's surface):
  // hypotheses lie from this far in front of it ...
  double prior_front_mm = 3;
  double prior_behind_mm = 25;  // ... to this far behind it
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

// One view as the stereo needs it; every map is full size.
struct MvsView {
  CameraIntrinsics camera;
  Rigid3d cam_from_object;
  cv::Mat1f grey;             // 0..255
  cv::Mat1f orientation_deg;  // [0, 180), NaN where unknown
  cv::Mat1b hair;             // non-zero on hair
  // Optional (empty, or 0 at a pixel = none): a depth (mm) the surface is
  // near, such as the visual hull's (reconstruction/visual_hull.h), read at
  // the grid's pixels.
  cv::Mat1f prior_depth_mm;
};

// A reference view's result on its grid (cols = ceil(width / stride)).
struct LineDepthMap {
  int stride_px = 2;
  cv::Mat1f depth_mm;           // along the optical axis; 0 where no hair or no estimate
  cv::Mat1f cost;               // the best hypothesis' cost, 0..1; 1 where none
  cv::Mat3f direction;          // unit 3D direction of the segment, object frame (unsigned)
  std::vector<int> neighbours;  // the views it was compared with
};

// The point of grid cell (gx, gy) of a map: its full-size pixel.
inline cv::Point2d GridPixel(const LineDepthMap& map, int gx, int gy) {
  return {static_cast<double>(gx * map.stride_px), static_cast<double>(gy * map.stride_px)};
}

// Progress: (views done, views in all), called from the worker threads.
using MvsProgress = std::function<void(int, int)>;

// Depth and direction maps of every view. Where a view has no prior depth,
// the search spans depth_margin_mm around the subject's centre, found by
// intersecting the rays through each view's hair centroid. InvalidArgument
// for fewer than two views, maps of the wrong size or bad options;
// FailedPrecondition when a view has no neighbour within the baselines.
Result<std::vector<LineDepthMap>> ComputeLineDepthMaps(const std::vector<MvsView>& views,
                                                       const LineMvsOptions& options,
                                                       const MvsProgress& progress = {});

// Views sorted as neighbours of `reference`: within the baselines, the
// closest viewing directions first, at most options.neighbours.
std::vector<int> NeighbourViews(const std::vector<MvsView>& views, int reference,
                                const LineMvsOptions& options);

}  // namespace hairrig
