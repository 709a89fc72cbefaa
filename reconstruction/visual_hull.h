// The visual hull of the subject (head and hair) from the views' silhouettes
// (Laurentini 1994): the voxels whose projection falls on the foreground in
// every view that can judge them, and that most views have in their frame.
// Hair is the subject's outer layer, so the hull's front surface seen from a
// view lies on or just in front of the hair there (in front where the hull
// cannot see a concavity): the multi-view stereo searches behind it instead
// of over the whole depth range.
//
// Frames and units as core/transform.h: the grid lives in the views' object
// frame, mm; depth maps are along each camera's optical axis.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

// What a silhouette pixel says about the space behind it.
enum SilhouetteValue : uint8_t {
  kSilhouetteEmpty = 0,    // backdrop: nothing of the subject on this ray
  kSilhouetteSubject = 1,  // hair or head
  kSilhouetteUnknown = 2,  // hidden (the calibration box may stand in front): carves nothing
};

struct SilhouetteView {
  CameraIntrinsics camera;
  Rigid3d cam_from_object;
  cv::Mat1b silhouette;  // SilhouetteValue per pixel, the camera's size
};

struct VisualHullOptions {
  double voxel_mm = 2.0;         // the hull's resolution
  double search_voxel_mm = 8.0;  // the coarse grid that finds the subject's bounds first
  double search_radius_mm =
      700;  // the coarse grid spans this far around the cameras' common target
  // A voxel is carved when more views than MaxEmptyViews() see it on the
  // backdrop: max_empty_views, or max_empty_share of the views if that is
  // more (a share, as the more views there are, the more of them a
  // segmentation error reaches). The points stage leaves the pixels its
  // segmentation is unsure of out of the carving instead
  // (PointReconstructionOptions::hull_uncertain_alpha), which loses less on
  // hair the segmentation gets right; a share of 0.06 (2 of 38 views) gave
  // curly_blond's points F1 at (2 mm, 20 deg) 0.53 -> 0.64 and the default
  // scene's 0.764 -> 0.750 (docs/accuracy.md, "Options of the points stage,
  // compared").
  int max_empty_views = 0;
  double max_empty_share = 0;
  // A voxel is kept only when at least this share of the views has it in
  // their frame (in front of the camera and inside the image). Every view
  // frames the subject, so space that few views see is not the subject's;
  // without this, the views of part of a turn would keep all the space that
  // the others' frames miss, in front of the subject included.
  double min_in_frame_share = 0.75;
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

// The views that may see a voxel on the backdrop without carving it, of
// `views` in all (VisualHullOptions::max_empty_views and max_empty_share).
int MaxEmptyViews(const VisualHullOptions& options, int views);

struct VisualHull {
  Eigen::Vector3d origin_mm =
      Eigen::Vector3d::Zero();  // the centre of voxel (0, 0, 0), object frame
  double voxel_mm = 0;
  int nx = 0, ny = 0, nz = 0;
  std::vector<uint8_t> occupied;  // x fastest, then y, then z

  bool Occupied(int x, int y, int z) const {
    return x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz &&
           occupied[(static_cast<size_t>(z) * static_cast<size_t>(ny) + static_cast<size_t>(y)) *
                        static_cast<size_t>(nx) +
                    static_cast<size_t>(x)] != 0;
  }
  // Occupancy at a point (the voxel containing it).
  bool OccupiedAt(const Eigen::Vector3d& p_object) const;
  int64_t OccupiedCount() const;
};

// Carves the hull. InvalidArgument for fewer than two views, a silhouette of
// another size than its camera, or bad options; FailedPrecondition when
// nothing survives (the silhouettes do not agree: a wrong calibration).
Result<VisualHull> CarveVisualHull(const std::vector<SilhouetteView>& views,
                                   const VisualHullOptions& options);

// Depth (mm along the optical axis) of the hull's first voxel on the ray of
// every `stride_px`-th pixel where `region` is non-zero (all such pixels when
// `region` is empty); 0 where the ray misses the hull and on pixels not
// sampled. Full size, CV_32F. Rays march at a quarter voxel, so the depth is
// within about a voxel of the hull's surface.
cv::Mat1f HullDepthMap(const VisualHull& hull, const CameraIntrinsics& camera,
                       const Rigid3d& cam_from_object, const cv::Mat& region, int stride_px);

}  // namespace hairrig
