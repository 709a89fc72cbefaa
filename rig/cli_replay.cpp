#include <cstdio>

#include <CLI/CLI.hpp>

#include "rig/cli.h"
#include "rig/replay_capture.h"

namespace hairrig {
namespace {

Result<nlohmann::json> RunReplay(const ReplayCaptureOptions& options) {
  HR_ASSIGN_OR_RETURN(ReplayCaptureSummary summary, ReplayCapture(options));
  return summary.ToJson();
}

void PrintReplay(const nlohmann::json& j) {
  std::printf("replayed %s (%d recorded frames) into %s: %s\n", j["replayed_from"].get<std::string>().c_str(),
              j["recorded_frames"].get<int>(), j["dir"].get<std::string>().c_str(), j["status"].get<std::string>().c_str());
  std::printf("  views %d of %d, %d frames, %.2f s\n", j["views_completed"].get<int>(), j["views_planned"].get<int>(),
              j["frames"].get<int>(), j["wall_s"].get<double>());
  if (!j["message"].get<std::string>().empty()) std::printf("  %s\n", j["message"].get<std::string>().c_str());
}

}  // namespace

void AddReplayCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "replay", "Run the capture sequencer on a recorded capture through the replay device backend (no hardware)");
  auto args = std::make_shared<ReplayCaptureOptions>();
  cmd->add_option("DIR", args->recorded_dir, "a capture folder made by `hairrig capture`")->required();
  cmd->add_option("--out", args->out_dir, "the new capture folder (default: DIR-replay); must not exist");
  cmd->add_option("--speed", args->speed, "0: as fast as possible (default); 1: recorded timing; 2: twice as fast")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunReplay(*args); };
    dispatch.print_human = PrintReplay;
    dispatch.exit_code = [](const nlohmann::json& j) { return j["status"] == "complete" ? 0 : 3; };
  });
}

}  // namespace hairrig
