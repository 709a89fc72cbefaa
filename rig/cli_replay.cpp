#include <cstdio>

#include <CLI/CLI.hpp>

#include "rig/capture.h"
#include "rig/cli.h"
#include "rig/replay.h"

namespace hairrig {
namespace {

struct ReplayArgs {
  std::string dir;
  std::string out;
  double speed = 0;
};

Result<nlohmann::json> RunReplay(const ReplayArgs& a) {
  CaptureOptions options;
  options.config_path = a.dir + "/rig.yaml";
  options.out_dir = a.out.empty() ? a.dir + "-replay" : a.out;
  HR_RETURN_IF_ERROR(CheckReplayOutDir(a.dir, options.out_dir));
  HR_ASSIGN_OR_RETURN(std::shared_ptr<ReplaySource> source, OpenReplaySource(a.dir, {.speed = a.speed}));
  options.rig_build.register_backends = [source](DeviceRegistry* registry) { RegisterReplayBackends(registry, source); };
  options.rig_build.backend_override = "replay";
  options.rig_build.simulate = false;
  HR_ASSIGN_OR_RETURN(CaptureSummary summary, RunCapture(options));
  nlohmann::json out = summary.ToJson();
  out["replayed_from"] = a.dir;
  out["recorded_frames"] = ReplayFrameCount(*source);
  return out;
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
  auto args = std::make_shared<ReplayArgs>();
  cmd->add_option("DIR", args->dir, "a capture folder made by `hairrig capture`")->required();
  cmd->add_option("--out", args->out, "the new capture folder (default: DIR-replay); must not exist");
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
