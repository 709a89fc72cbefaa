// `hairrig stage <name> --capture DIR`: one pipeline stage of one capture
// (batch/stage.h), the job `hairrig batch` runs per capture and stage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "batch/process.h"
#include "batch/stage.h"
#include "cli/cli.h"

namespace hairrig {
namespace {

struct StageArgs {
  std::string stage;
  std::string capture;
  std::string options;
  std::string run_id;
  bool force = false;
};

Result<nlohmann::json> RunStageCommand(const StageArgs& a) {
  StageOptions options;
  HR_ASSIGN_OR_RETURN(options.stage, ParseStage(a.stage));
  options.capture_dir = a.capture;
  HR_ASSIGN_OR_RETURN(options.settings, LoadStageSettings(a.options));
  options.run_id = a.run_id;
  options.force = a.force;
  HR_ASSIGN_OR_RETURN(options.hairrig_exe, SelfExecutable());
  HR_ASSIGN_OR_RETURN(const StageResult result, RunStage(options));
  nlohmann::json j = result.ToJson();
  j["brief"] = result.BriefReport();
  return j;
}

}  // namespace

void AddStageCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto args = std::make_shared<StageArgs>();
  CLI::App* cmd = app.add_subcommand(
      "stage",
      "run one pipeline stage of one capture (calibrate, reconstruct, fit, simulate), record it in "
      "DIR/<stage folder>/result.json; skipped when its inputs are unchanged since its last "
      "success");
  cmd->add_option("STAGE", args->stage, "calibrate, reconstruct, fit or simulate")
      ->required()
      ->check(CLI::IsMember({"calibrate", "reconstruct", "fit", "simulate"}));
  cmd->add_option("--capture", args->capture, "the capture folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--options", args->options,
                  "stage options (a JSON file, batch/stages.h; default: the defaults)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--run-id", args->run_id,
                  "recorded in result.json (`hairrig batch` passes its submission's)");
  cmd->add_flag("--force", args->force, "run even when the inputs are unchanged");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunStageCommand(*args); };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("%s\n", j["brief"].get<std::string>().c_str());
    };
  });
}

}  // namespace hairrig
