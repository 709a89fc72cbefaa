// The stage contract (docs/design.md section 10): `hairrig stage <name> --capture
// DIR` runs one stage of one capture, writes its outputs inside DIR (the
// folders of batch/stages.h), records the run in <folder>/result.json
// (batch/stage_record.h) and fails with a Status (a non-zero exit) when the
// stage fails.
//
// Inputs and skipping: the stage's input hash is a SHA-256 over the hairrig
// version and build (core/version.h), the stage's name, its options (without `threads` and the file
// names) and the SHA-256 of every input file, named by its path inside the
// capture (or by the option that names it), so it does not depend on where
// the capture or the option files lie:
//
//   calibrate    rig.yaml, manifest.json, frames/*, the `intrinsics` files
//   reconstruct  rig.yaml, manifest.json, frames/*, calibration/calibration.json, the `head` file
//   fit          reconstruction/strands/strands.ply
//   simulate     fit/model.json, reconstruction/strands/strands.ply, the head and scene files
//
// frames/* are the files in frames/ that stay inside the capture folder once
// their symlinks are resolved; a frames/ folder leading outside it refuses the
// stage (rig/manifest_frames.h).
//
// Files that rig.yaml names (the calibration box, a head file) count by their
// name in rig.yaml's text, not by their contents. When the hash equals the one
// of the last successful run (result.json status ok) the stage does not run:
// the record is kept, marked skipped, with the new run id.
//
// Test hook, for fault injection: when the environment variable
// HAIRRIG_STAGE_FAULT holds "<stage>:<capture folder name>" (several joined
// by commas) a matching stage fails at once, before reading anything, with an
// error that says so; result.json records it with "injected_fault": true.
// Unset, it has no effect.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

// The test hook's environment variable (above).
inline constexpr const char* kStageFaultVariable = "HAIRRIG_STAGE_FAULT";

struct StageOptions {
  Stage stage = Stage::kCalibrate;
  std::string capture_dir;
  StageSettings settings;
  std::string run_id;  // recorded in result.json: the batch submission running the stage
  bool force = false;  // run even when the inputs are unchanged
  std::string
      hairrig_exe;  // the hairrig binary; the simulate stage runs it (batch/simulate_stage.h)

  // InvalidArgument naming the field: no capture_dir, the stage's threads
  // outside 1..1024 (named as in the stage options file: "fit.threads").
  Status Check() const;
};

struct StageResult {
  Stage stage = Stage::kCalibrate;
  std::string capture_dir;
  std::string result_file;  // the record written
  std::string input_hash;
  bool skipped = false;    // inputs unchanged since the last success: nothing ran
  double seconds = 0;      // of this call
  nlohmann::json summary;  // the stage's summary (a skipped stage: the last success's)

  nlohmann::json ToJson() const;
  // One line: "reconstruct of /x/cap1: ok in 12.3 s (result: ...)".
  std::string BriefReport() const;
};

// The capture folder's name, as HAIRRIG_STAGE_FAULT matches it: the last
// component of the normalised path.
std::string CaptureName(const std::string& capture_dir);

// The input files of `stage` for `capture_dir` with `settings`: name -> path
// (names as listed above). FailedPrecondition names a missing input and the
// stage that writes it; NotFound for a missing capture folder.
Result<std::map<std::string, std::string>> StageInputFiles(Stage stage,
                                                           const std::string& capture_dir,
                                                           const StageSettings& settings);

// Runs the stage (above). A failure is returned as its Status, prefixed with
// "<stage> of <capture>", after result.json has recorded it (when the stage
// folder can be written).
Result<StageResult> RunStage(const StageOptions& options);

}  // namespace hairrig
