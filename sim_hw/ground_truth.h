// Ground truth of the simulated rig, written beside simulated captures and
// renders and clearly marked simulation-only. Frames as in core/transform.h.
#pragma once

#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/head_spec.h"
#include "core/status.h"
#include "core/transform.h"
#include "core/truth_maps.h"
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
ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view, int stop, int camera_index,
                                    double turntable_deg);

// JSON text: {"simulation_only": true, "scene": ..., "turntable_from_box": ...,
// "head": ..., "views": [...]}, and with `with_maps` a "maps" entry that
// documents the per-pixel files below (format version, file names, units and
// scales). "head" is the scene's head (core/head_json.h) with its mesh, if it
// has one, named as WriteTruthHeadMesh copies it beside the JSON file.
std::string GroundTruthJson(const Scene& scene, const std::vector<ViewGroundTruth>& views,
                            bool with_maps = false);

// The name of the head's mesh in a ground truth folder: "head_mesh.ply" (or
// "head_mesh.obj" for an OBJ mesh, copied as it is); "" for an ellipsoid head.
std::string TruthHeadMeshName(const HeadSpec& head);
// Copies the scene head's mesh file to <truth_dir>/TruthHeadMeshName(...)
// (written atomically with `write`, core/capture_storage.h; empty: the file
// system; nothing for an ellipsoid head). Errors name the file.
Status WriteTruthHeadMesh(const Scene& scene, const std::string& truth_dir,
                          const FileWriter& write = {});

}  // namespace hairrig
