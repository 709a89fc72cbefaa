// `hairrig simulate`: super-helix dynamics of a fitted model
// (simulation/hair_simulation.h) over a scenario, the full hairstyle
// interpolated from the guides (simulation/guide_interpolation.h), written
// as a strand file per frame and a preview image every few frames, with a
// summary. Output folder:
//   frames/frame_NNNN.hair     the strands of frame N, model frame, mm
//   guides/frame_NNNN.hair     the guides of frame N (the dynamics' curves,
//                              4 points per helix element), when frames/
//                              holds strands interpolated from them
//   previews/frame_NNNN.png    the strands drawn by the registered previewer
//                              (rig/simulation_preview.h: the scene's first camera),
//                              the head as the scene (or head_file) gives it
//   summary.json               SimulateRunSummary::ToJson()
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/status.h"
#include "simulation/hair_simulation.h"

namespace hairrig {

struct SimulateRunOptions {
  std::string model_file;  // from `hairrig fit` (simulation/helix_model.h)
  std::string out_dir;     // must not exist, or be empty
  Scenario scenario = Scenario::kGravity;
  double seconds = 2;  // simulated time
  double fps = 30;     // frames written per simulated second; frame 0 is the rest state
  double time_step_s = 1.0 / 240;
  LinearSolver solver = LinearSolver::kCholesky;  // of Eq. 11
  // The scene file giving the head (contact, the shake's pivot) and the
  // preview camera; empty: etc/scenes/default.yaml.
  std::string scene_file;
  // A head file (core/head_config.h) replacing the scene's head, for contact
  // with its surface and in the previews; empty: the scene's ellipsoid.
  std::string head_file;
  bool head_contact = true;
  Eigen::Vector3d up{0, 0, 1};  // world up; any non-zero length
  int preview_every = 1;        // a preview every this many frames; 0: none
  int threads = 0;              // guides stepped in parallel; 0: one thread per core
  // Write the guides only, not the full hairstyle of the model's source
  // strands (read from where `fit` recorded them or beside the model; the
  // guides are written when they cannot be read, with a warning).
  bool guides_only = false;
  // The interpolated strands keep their segments' rest lengths
  // (GuideInterpolationOptions::keep_lengths); false: the plain blend.
  bool keep_lengths = true;

  // InvalidArgument naming the field and its range.
  Status Check() const;
};

struct SimulateRunSummary {
  std::string out_dir;
  std::string model_file;
  Scenario scenario = Scenario::kGravity;
  double seconds = 0, fps = 0;
  int frames = 0;
  double time_step_s = 0;
  int guides = 0;
  size_t strands = 0;  // per frame: the full hairstyle's, or the guides'
  bool interpolated = false;
  double interpolation_rest_fit_rms_mm = 0;  // 0 when not interpolated
  bool head_contact = false;
  HairSimulationStats stats;
  double dynamics_wall_s = 0;  // stepping the dynamics only
  double max_tip_move_mm = 0;  // largest distance of a guide's tip from its rest position
  // The written strands' length over their rest length, over every frame:
  // the largest per-frame 99th percentile, and the largest. 1 up to rounding
  // for the guides (inextensible) and for strands interpolated with
  // keep_lengths; above 1 where the plain blend stretches them.
  double strand_stretch_p99 = 0, strand_stretch_max = 0;

  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: options (named), out_dir not empty, the model's, the scene's or the
// head file's (named), a model the dynamics refuse (the guide named), a frame
// whose step fails (numbered), a file that cannot be written (named).
Result<SimulateRunSummary> SimulateRun(const SimulateRunOptions& options);

}  // namespace hairrig
