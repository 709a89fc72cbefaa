#include <CLI/CLI.hpp>

#include "cli/cli.h"
#include "rig/replay_capture.h"

namespace hairrig {

void AddReplayCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("replay",
                                 "Run the capture sequencer on a recorded capture through the "
                                 "replay device backend (no hardware)");
  auto args = std::make_shared<ReplayCaptureOptions>();
  cmd->add_option("DIR", args->recorded_dir, "a capture folder made by `hairrig capture`")
      ->required();
  cmd->add_option("--out", args->out_dir,
                  "the new capture folder (default: DIR-replay); must not exist");
  cmd->add_option("--speed", args->speed,
                  "0: as fast as possible (default); 1: recorded timing; 2: twice as fast")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    DispatchSummary(dispatch, [args] { return ReplayCapture(*args); });
    dispatch.exit_code = [](const nlohmann::json& j) { return j["status"] == "complete" ? 0 : 3; };
  });
}

}  // namespace hairrig
