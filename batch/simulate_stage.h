// The simulate stage's one call into the dynamics: a fitted model to frames,
// previews and summary.json, exactly as `hairrig simulate MODEL --out DIR`
// with the settings' flags. It runs that command as a child process of the
// hairrig binary, which holds the dynamics' driver (cli/cli_simulate.cpp).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

struct SimulateStageRequest {
  std::string model;          // a helix model written by the fit stage
  std::string out_dir;        // written by the dynamics; absent or empty
  SimulateSettings settings;  // head and scene: files, or empty for the command's defaults
  std::string hairrig_exe;    // the hairrig binary
};

// The summary `hairrig simulate --json` prints (also in <out_dir>/summary.json).
// The model's relative `source` (its strands) resolves against the model's
// folder. Errors: NotFound naming the binary when it cannot be started;
// the command's own error (a bad model, a folder that cannot be written)
// with its message; CorruptData when its summary cannot be read.
Result<nlohmann::json> RunSimulateForStage(const SimulateStageRequest& request);

}  // namespace hairrig
