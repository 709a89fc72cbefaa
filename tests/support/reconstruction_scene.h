// Test helper: a reduced simulated capture for the reconstruction's tests.
// The default scene with its cameras at `scale` of their resolution (the same
// field of view), a thinner wig and fewer turntable stops is rendered into
// <dir>/ground_truth/ as `hairrig sim render --all` does (images, per-pixel
// maps, true strands), and its views are given to the reconstruction with
// the true cameras in the turntable frame, as a perfect calibration would.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/calib_box.h"
#include "core/truth_maps.h"
#include "reconstruction/hair_segmentation.h"
#include "reconstruction/views.h"
#include "sim_hw/scene_variations.h"
#include "sim_hw/view_set.h"
#include "tests/support/default_scene.h"

namespace hairrig_test {

struct ReducedCaptureOptions {
  double scale = 0.5;
  int strands = 10000;
  int stops = 12;
  // sim_hw/scene_variations.h names, applied after the reductions.
  std::vector<std::string> variations;

  // InvalidArgument naming the field: scale outside (0, 1], strands or stops below 1.
  hairrig::Status Check() const {
    if (!(scale > 0 && scale <= 1)) return hairrig::InvalidArgument("scale must lie in (0, 1]");
    if (strands < 1) return hairrig::InvalidArgument("strands must be at least 1");
    if (stops < 1) return hairrig::InvalidArgument("stops must be at least 1");
    return hairrig::Status::Ok();
  }
};

inline hairrig::Scene ReducedScene(const ReducedCaptureOptions& o) {
  hairrig::Scene scene = DefaultScene();
  scene.wig.num_strands = o.strands;
  scene.turntable_stops = o.stops;
  for (hairrig::SceneCamera& c : scene.cameras) {
    hairrig::CameraIntrinsics& k = c.intrinsics;
    k.width_px = static_cast<int>(k.width_px * o.scale);
    k.height_px = static_cast<int>(k.height_px * o.scale);
    k.fx_px *= o.scale;
    k.fy_px *= o.scale;
    k.cx_px = (k.cx_px + 0.5) * o.scale - 0.5;
    k.cy_px = (k.cy_px + 0.5) * o.scale - 0.5;
  }
  const hairrig::Status varied = hairrig::ApplySceneVariations(o.variations, &scene);
  EXPECT_TRUE(varied.ok()) << varied.ToString();
  return scene;
}

// Renders the reduced capture into <dir>/ground_truth/ and returns its views.
inline hairrig::ReconstructionInput RenderReducedCapture(const std::string& dir,
                                                         const ReducedCaptureOptions& o) {
  namespace fs = std::filesystem;
  const hairrig::Status valid = o.Check();
  EXPECT_TRUE(valid.ok()) << valid.ToString();
  if (!valid.ok()) return {};
  const std::string truth_dir = dir + "/ground_truth";
  fs::create_directories(truth_dir);
  const hairrig::Scene scene = ReducedScene(o);
  auto renderer = hairrig::Renderer::Create(scene);
  EXPECT_TRUE(renderer.ok()) << renderer.status().ToString();
  if (!renderer.ok()) return {};
  auto rendered = hairrig::RenderAllViews(**renderer, truth_dir, {});
  EXPECT_TRUE(rendered.ok()) << rendered.status().ToString();
  auto truth = hairrig::ReadCaptureTruth(dir);
  EXPECT_TRUE(truth.ok()) << truth.status().ToString();
  if (!rendered.ok() || !truth.ok()) return {};
  const auto corners = hairrig::BoxCornerPoints(0.5 * scene.box.size_mm);
  const std::vector<Eigen::Vector3d> box_corners(corners.begin(), corners.end());
  hairrig::ReconstructionInput input;
  input.object_frame = "turntable";
  input.object_from_box = truth->turntable_from_box;
  const hairrig::Rigid3d box_from_turntable = truth->turntable_from_box.Inverse();
  for (const auto& [view, t] : truth->views) {
    hairrig::ReconstructionView v;
    v.id = view;
    const std::string file = hairrig::ViewFileName(view, t.camera_serial);
    v.name = fs::path(file).stem().string();
    v.image_path = truth_dir + "/" + file;
    v.camera = t.intrinsics;
    v.cam_from_object = t.cam_from_box * box_from_turntable;
    v.not_hair_px.push_back(hairrig::ProjectedOutline(t.intrinsics, t.cam_from_box, box_corners));
    input.views.push_back(v);
  }
  return input;
}

}  // namespace hairrig_test
