// Renders every view of the default plan of a scene to a folder, with a
// contact sheet and the ground truth (`hairrig sim render --all`), or one
// view to an image file (`hairrig sim render --view N`).
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "sim_hw/renderer.h"

namespace hairrig {

struct RenderViewsOptions {
  int threads = 2;
  bool noise = true;
  std::vector<double> light_levels;  // empty: all panels on

  // InvalidArgument naming the field: threads below 1, a light level outside 0..1.
  Status Check() const;
};

struct RenderViewsSummary {
  int views = 0;
  std::vector<std::string> files;  // relative to the output folder
  std::string contact_sheet;       // "contact_sheet.png"
  std::string ground_truth;        // "ground_truth.json"
  double wall_s = 0;
};

// Writes <out>/<view>_<serial>.png for every view (view = stop * cameras +
// camera, three digits), contact_sheet.png, ground_truth.json, head_mesh.ply
// (a mesh head's mesh), ground_truth_strands.ply (turntable frame) and the per-pixel maps of every
// view in <out>/views/ (sim_hw/ground_truth.h), and last checksums.json, the SHA-256 of
// every file under <out> (core/truth_maps.h). `out` must exist. InvalidArgument
// for bad options (RenderViewsOptions::Check).
Result<RenderViewsSummary> RenderAllViews(const Renderer& renderer, const std::string& out_dir,
                                          const RenderViewsOptions& options);

struct RenderSceneViewsOptions {
  std::string scene_file;  // the scene (sim_hw/scene.h)
  std::string out_dir;     // created
  RenderViewsOptions render;

  // InvalidArgument naming the field: no scene or folder, bad render options.
  Status Check() const;
};

struct RenderSceneViewsSummary {
  std::string out_dir;
  RenderViewsSummary views;
  size_t strands = 0;  // of the scene's wig

  // views, out, contact_sheet and ground_truth (paths under out), strands,
  // wall_s, seconds_per_view.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// RenderAllViews of the scene's renderer into out_dir. Errors: the scene's
// (named), a folder or file that cannot be written (named).
Result<RenderSceneViewsSummary> RenderSceneViews(const RenderSceneViewsOptions& options);

struct RenderViewFileOptions {
  std::string scene_file;           // the scene (sim_hw/scene.h)
  int view = 0;                     // in the scene's default plan: stop * cameras + camera
  std::string out_file;             // .png, .tif, .tiff or .jpg
  bool noise = true;                // sensor noise, seeded by the scene's seed and the view
  std::optional<cv::Rect> crop_px;  // only these pixels, at full resolution; inside the view

  // InvalidArgument naming the field: no scene, a negative view, an output
  // that is not an image file name, an empty crop.
  Status Check() const;
};

struct RenderViewFileSummary {
  int view = 0;
  std::string camera_serial;
  double turntable_deg = 0;
  std::string out_file;
  int width_px = 0, height_px = 0;  // of the image written
  int tags_unoccluded = 0;          // the box's tags the view sees whole

  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: the scene's (named), a view outside the plan or a crop outside the
// view (InvalidArgument with the allowed range), the file's (named).
Result<RenderViewFileSummary> RenderViewFile(const RenderViewFileOptions& options);

// "007_SIM-CAM-UPPER.png"
std::string ViewFileName(int view, const std::string& serial);

}  // namespace hairrig
