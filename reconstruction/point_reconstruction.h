// Reconstruction I: from calibrated views to a cloud of oriented 3D points
// (docs/design.md section 6), each step a library call of its own:
//
//   per view   hair segmentation (hair_segmentation.h) -> masks/
//              2D orientation map (orientation_map.h)  -> orientation/
//   all views  visual hull of the subject's silhouettes (visual_hull.h)
//              line multi-view stereo behind the hull (line_mvs.h) -> depth/
//              fusion of the views' maps (point_fusion.h) -> points.ply
//   pictures   report/: each view with its hair outline and the points it
//              sees, coloured by direction
//   summary    summary.json
//
// This replaces Luo 2013 Sec. 4's PMVS point cloud by line-based MVS (Nam et
// al. 2019) searched behind the visual hull; Luo's 3D orientation per point
// is the line MVS's segment direction.
//
// Output layout under `out_dir` (created):
//   masks/<view>_label.png         8-bit: 0 backdrop, 1 box, 2 head, 3 hair
//   masks/<view>_alpha.png         16-bit: hair coverage x 65535
//   orientation/<view>_angle.png   16-bit: deg x 100 in [0, 18000); 65535 where unknown
//   orientation/<view>_confidence.png  16-bit: confidence x 65535
//   orientation/<view>.jpg         hue = angle, brightness = confidence
//   depth/<view>_depth.png         16-bit: mm x 20 on the MVS grid (every stride-th pixel); 0 =
//   none depth/<view>.jpg               the depth as a colour map points.ply point_cloud.h
//   report/<view>.jpg              half size: hair outline and projected points
//   summary.json                   PointReconstructionSummary::ToJson()
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "reconstruction/hair_segmentation.h"
#include "reconstruction/line_mvs.h"
#include "reconstruction/orientation_map.h"
#include "reconstruction/point_fusion.h"
#include "reconstruction/views.h"
#include "reconstruction/visual_hull.h"

namespace hairrig {

struct PointReconstructionOptions {
  SegmentationOptions segmentation;
  OrientationOptions orientation;
  // Hair pixels whose orientation confidence is below this take no part in
  // the stereo (their direction is noise).
  double min_orientation_confidence = 0.0;
  // Backdrop pixels whose hair coverage (HairSegmentation::hair_alpha) is at
  // least this carve nothing from the visual hull: the segmentation is
  // unsure there. Thin wisps it misses lie in that band (curly_blond: the
  // true hair pixels labelled backdrop have a coverage of 0.39-0.41 at the
  // median), so they do not put the hull's surface behind the hair. 1 lets
  // every backdrop pixel carve.
  double hull_uncertain_alpha = 0.25;
  VisualHullOptions hull;
  LineMvsOptions mvs;
  FusionOptions fusion;
  bool write_pictures = true;  // orientation/*.jpg, depth/*.jpg, report/
  // Threads for every step (the steps' own `threads` fields are set from it).
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct ViewPointsSummary {
  std::string name;
  int hair_pixels = 0;        // segmented as hair
  int stereo_pixels = 0;      // ... with a confident orientation: the stereo's input
  bool capture_skin = false;  // segmented with the capture's skin model (too little skin seen)
  int64_t capture_skin_pixels = 0;           // pixels that model turned from hair to skin
  double median_orientation_confidence = 0;  // over the hair pixels, 0..1 (OrientationMap)
  int depth_cells = 0;                       // grid cells with a depth under the fusion's max_cost
  double median_cost = 0;                    // of those cells
  int points_seen = 0;                       // fused points this view sees
};

struct PointReconstructionSummary {
  std::string object_frame;
  std::optional<Rigid3d> object_from_box;  // ReconstructionInput's
  int stride_px = 0;                       // the depth maps' grid step
  double min_orientation_confidence = 0;
  int orientation_scales = 0;           // OrientationOptions::scales used
  double orientation_smoothing_px = 0;  // OrientationOptions::smoothing_px used
  std::vector<std::string> left_out;    // "view: why"
  std::vector<ViewPointsSummary> views;
  int64_t hull_voxels = 0;
  double hull_voxel_mm = 0;
  FusionSummary fusion;
  double segmentation_s = 0, hull_s = 0, stereo_s = 0, fusion_s = 0, writing_s = 0, total_s = 0;
  std::string points_file;  // out_dir/points.ply

  nlohmann::json ToJson() const;
  std::string BriefReport() const;  // a few lines for a person
};

// The visual hull's silhouette of one view from its segmentation: hair and
// head are the subject; the calibration box, and backdrop whose hair
// coverage is at least `uncertain_alpha`, carve nothing (kSilhouetteUnknown);
// the rest is backdrop.
cv::Mat1b SilhouetteOf(const HairSegmentation& segmentation, double uncertain_alpha);

// The figures of a points stage's summary.json that the reconstruction's
// verdict reads (reconstruction_verdict.h): each view's name and median
// orientation confidence, and the fusion's counts; for a run of the strands
// stage alone. NotFound when the file is absent; CorruptData naming the file
// and field when a figure is missing or malformed (a summary written before
// the verdict: run the points stage again).
Result<PointReconstructionSummary> ReadPointSummaryFigures(const std::string& path);

// (stage, done, total): stage is "segmentation", "hull", "stereo", "fusion" or "writing".
using ReconstructionProgress = std::function<void(const std::string&, int, int)>;

// Runs every step. Views whose image cannot be read, is of another size than
// its camera, shows no hair or cannot be segmented are left out and named in
// the summary; InvalidArgument for bad options; FailedPrecondition when fewer
// than two views remain or the silhouettes do not meet; IoError naming the
// file for an output that cannot be written.
Result<PointReconstructionSummary> ReconstructPoints(const ReconstructionInput& input,
                                                     const std::string& out_dir,
                                                     const PointReconstructionOptions& options,
                                                     const ReconstructionProgress& progress = {});

}  // namespace hairrig
