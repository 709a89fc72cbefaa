// The pipeline's stages as batch jobs (docs/design.md section 10) and their
// options. Each stage reads and writes inside one capture folder:
//
//   stage        writes (inside the capture)   as the command line does
//   calibrate    calibration/                  hairrig calibrate DIR
//   reconstruct  reconstruction/               hairrig reconstruct DIR
//   fit          fit/model.json                hairrig fit DIR/reconstruction/strands/strands.ply
//   simulate     simulation/<scenario>/        hairrig simulate DIR/fit/model.json
//
// and records its run in <folder>/result.json (batch/stage_record.h).
//
// The options come from a JSON file whose every section and field is
// optional (the defaults are the command line's, and scripts/demo's for fit
// and simulate):
//
//   {"calibrate":   {"mode": "turntable", "intrinsics": ["cam.json"], "hard_prior": false,
//                    "threads": 2},
//    "reconstruct": {"method": "bao-qi", "strands": 40000, "head": "", "stride_px": 3,
//                    "iterations": 4, "hull_voxel_mm": 2.0, "threads": 2},
//    "fit":         {"guides": 300, "target_error_mm": 0.05, "threads": 2},
//    "simulate":    {"scenario": "head-shake", "seconds": 1, "fps": 30, "preview_every": 1,
//                    "head": "", "scene": ""}}
//
// Relative file names resolve against the options file's folder. A stage's
// options enter its input hash, except `threads` and file names (the files'
// contents do: batch/stage.h). With "threads": 1 every stage repeats bit
// for bit on the same binary and CPU type (tests/batch_slurm checks it);
// with more, bit-for-bit repetition is not checked.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/status.h"
#include "reconstruction/line_mvs.h"
#include "reconstruction/strand_reconstruction.h"
#include "reconstruction/visual_hull.h"

namespace hairrig {

enum class Stage { kCalibrate, kReconstruct, kFit, kSimulate };

// Every stage, in pipeline order: a stage reads what the earlier ones wrote.
inline constexpr std::array<Stage, 4> kAllStages = {Stage::kCalibrate, Stage::kReconstruct,
                                                    Stage::kFit, Stage::kSimulate};

// "calibrate", "reconstruct", "fit", "simulate".
const char* StageName(Stage stage);
// The folder inside the capture that holds the stage's outputs and result.json:
// "calibration", "reconstruction", "fit", "simulation".
const char* StageFolder(Stage stage);
// InvalidArgument listing the stages.
Result<Stage> ParseStage(const std::string& name);
// Names (each may also be a comma-separated list) to stages in pipeline order,
// each once; empty: every stage.
Result<std::vector<Stage>> ParseStageList(const std::vector<std::string>& names);

struct CalibrateSettings {
  std::string mode = "turntable";  // turntable or free (`calibrate --mode`)
  std::vector<std::string>
      intrinsics;           // files whose intrinsics are held (`calibrate --intrinsics`)
  bool hard_prior = false;  // `calibrate --hard-prior`
  int threads = 2;          // detection and solver threads
};

struct ReconstructSettings {
  std::string method = "bao-qi";  // bao-qi, luo or naive (`reconstruct --method`)
  int strands = StrandReconstructionOptions{}.strands;  // strands grown (`reconstruct --strands`)
  // The subject's head file; "fit": fitted to the views; empty: the capture's
  // rig.yaml head (fitted where it has none).
  std::string head;
  int stride_px =
      LineMvsOptions{}.stride_px;  // stereo on every N-th pixel (`reconstruct --stride`)
  int iterations =
      LineMvsOptions{}.iterations;  // stereo PatchMatch iterations (`reconstruct --iterations`)
  double hull_voxel_mm = VisualHullOptions{}.voxel_mm;  // the visual hull's voxel size
  int threads = 2;
};

struct FitSettings {
  int guides = 300;               // guide strands K (`fit --guides`)
  double target_error_mm = 0.05;  // `fit --target-error`
  int threads = 2;                // guides fitted in parallel
};

struct SimulateSettings {
  std::string scenario = "head-shake";  // gravity, head-shake or wind
  double seconds = 1;                   // simulated time
  double fps = 30;                      // frames written per simulated second
  int preview_every = 1;                // a preview image every N frames; 0: none
  // The head for contact and previews; empty: the head file the capture's
  // rig.yaml names (none when its head is written inline or absent: then the
  // scene's ellipsoid, as `hairrig simulate` without --head).
  std::string head;
  std::string scene;  // the scene of the preview camera; empty: etc/scenes/default.yaml
};

struct StageSettings {
  CalibrateSettings calibrate;
  ReconstructSettings reconstruct;
  FitSettings fit;
  SimulateSettings simulate;

  // Every field of one stage's section.
  nlohmann::json StageJson(Stage stage) const;
  // Every section, every field: what LoadStageSettings reads back as these settings.
  nlohmann::json ToJson() const;
  // The CPU cores the stage uses (its `threads`; 1 for simulate).
  int Threads(Stage stage) const;
};

// Reads the sections of `j` over the defaults. `where` names the document in
// messages; relative file names resolve against `base_dir`. CorruptData names
// the field: an unknown section or field, a wrong type, a value out of range
// or not one of its choices.
Result<StageSettings> StageSettingsFromJson(const nlohmann::json& j, const std::string& where,
                                            const std::string& base_dir);
// The options file `path` (JSON, as above); "" gives the defaults.
Result<StageSettings> LoadStageSettings(const std::string& path);

}  // namespace hairrig
