// Ground truth of the simulated rig, written beside simulated captures and
// renders and clearly marked simulation-only. Frames as in core/transform.h.
#pragma once

#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/transform.h"
#include "sim_hw/renderer.h"
#include "sim_hw/scene.h"

namespace hairrig {

struct ViewGroundTruth {
  int view = 0;  // stop * num_cameras + camera
  int stop = 0;
  int camera_index = 0;
  std::string camera_serial;
  double turntable_deg = 0;
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_world;
  Rigid3d world_from_turntable;
  Rigid3d cam_from_box;
  std::vector<TagTruth> tags;
};

// The view numbering of the default plan: at each stop every camera shoots.
int NumViews(const Scene& scene);
ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view);
// Any plan: the view's camera (index into scene.cameras) at a turntable angle.
ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view, int stop, int camera_index, double turntable_deg);

// JSON text: {"simulation_only": true, "scene": ..., "turntable_from_box": ...,
// "views": [...]}, and with `with_maps` a "maps" entry that documents the
// per-pixel files below (format version, file names, units and scales).
std::string GroundTruthJson(const Scene& scene, const std::vector<ViewGroundTruth>& views, bool with_maps = false);

// Per-pixel ground truth of one view, lossless, in `dir` (created if missing):
//   NNN_label.png        8-bit: 0 backdrop, 1 box, 2 head, 3 hair
//   NNN_alpha.png        16-bit: hair coverage x 65535
//   NNN_orientation.png  16-bit: 2D strand direction in deg x 100 ([0, 18000)); 65535 where no strand
//   NNN_depth.png        16-bit: depth of the front-most surface in mm x kTruthDepthScale; 0 on the backdrop
//   NNN_strand.png       16-bit: front-most strand index + 1; 0 where no strand
// NNN is the view number (three digits). A wig of 65,535 strands or more
// cannot be written (OutOfRange), nor a depth past 3,276 mm.
constexpr int kTruthMapsVersion = 1;
constexpr double kTruthDepthScale = 20.0;  // 1/20 mm per count
Status WriteViewTruthMaps(const std::string& dir, int view, const ViewTruthMaps& maps);
// Reads what WriteViewTruthMaps wrote (the same units as ViewTruthMaps; the
// depth quantised to 0.05 mm, the angle to 0.01 deg). Errors name the file.
Result<ViewTruthMaps> ReadViewTruthMaps(const std::string& dir, int view);

}  // namespace hairrig
