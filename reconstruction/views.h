// The input of the reconstruction: calibrated views, whichever rig or tool
// calibrated them. A capture of this rig gives the turntable frame as object
// frame (rig/ builds the views from calibration/calibration.json); a COLMAP
// text model gives its own world frame (colmap_model.h).
//
// Frames and units as core/transform.h: mm, px, pixel (0,0) is the centre of
// the top-left pixel. Images are used as captured: the lens model (Brown-
// Conrady, core/camera_model.h) maps every 3D point to its distorted pixel.
#pragma once

#include <cstddef>
#include <opencv2/core/types.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/transform.h"

namespace hairrig {

// The fewest usable views a reconstruction runs on: the line stereo needs two.
inline constexpr size_t kMinStereoViews = 2;

struct ReconstructionView {
  int id = 0;              // the capture's view number, or COLMAP's IMAGE_ID
  std::string name;        // e.g. "012_SIM-CAM-UPPER": names outputs and messages
  std::string image_path;  // 8-bit grey or colour, camera.width_px x camera.height_px
  std::string
      mask_path;  // optional: a given hair mask (non-zero = hair), used instead of segmenting
  CameraIntrinsics camera;
  Rigid3d cam_from_object;
  // Image regions known not to be hair (the calibration box's projected
  // outline): polygons in pixels, each closed implicitly.
  std::vector<std::vector<cv::Point2f>> not_hair_px;
};

struct ReconstructionInput {
  std::string object_frame;  // "turntable" or "colmap world": what points.ply's coordinates are in
  // Where the object frame stands on the calibration box, when a capture's
  // calibration says it (the simulated rig's ground truth is tied to the box).
  std::optional<Rigid3d> object_from_box;
  std::vector<ReconstructionView> views;
  // Views that cannot be used, each "name: why" (a failed calibration, a
  // missing frame); the rest are reconstructed.
  std::vector<std::string> left_out;
};

}  // namespace hairrig
