// Renders every view of the default plan of a scene to a folder, with a
// contact sheet and the ground truth: what `hairrig sim render --all` does.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "core/status.h"
#include "sim_hw/renderer.h"

namespace hairrig {

struct RenderViewsOptions {
  int threads = 2;
  bool noise = true;
  std::vector<double> light_levels;  // empty: all panels on
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
// view in <out>/views/ (sim_hw/ground_truth.h). `out` must exist.
Result<RenderViewsSummary> RenderAllViews(const Renderer& renderer, const std::string& out_dir,
                                          const RenderViewsOptions& options);

// "007_SIM-CAM-UPPER.png"
std::string ViewFileName(int view, const std::string& serial);

}  // namespace hairrig
