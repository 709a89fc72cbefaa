#include "batch/simulate_stage.h"

#include <filesystem>

#include "batch/process.h"
#include "core/json_file.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// A number as the shortest text that reads back as the same double.
std::string NumberText(double value) { return nlohmann::json(value).dump(); }

std::vector<std::string> SimulateArgv(const SimulateStageRequest& r) {
  const SimulateSettings& s = r.settings;
  std::vector<std::string> argv{r.hairrig_exe,
                                "--log-level",
                                "warning",
                                "simulate",
                                r.model,
                                "--out",
                                r.out_dir,
                                "--scenario",
                                s.scenario,
                                "--seconds",
                                NumberText(s.seconds),
                                "--fps",
                                NumberText(s.fps),
                                "--preview-every",
                                std::to_string(s.preview_every),
                                "--threads",  // the one CPU the stage asks a scheduler for
                                "1",
                                "--json"};
  if (!s.head.empty()) argv.insert(argv.end(), {"--head", s.head});
  if (!s.scene.empty()) argv.insert(argv.end(), {"--scene", s.scene});
  return argv;
}

}  // namespace

Result<nlohmann::json> RunSimulateForStage(const SimulateStageRequest& request) {
  if (request.hairrig_exe.empty())
    return InvalidArgument("the simulate stage needs the hairrig binary's path");
  ProcessOptions options;
  options.working_dir = fs::path(request.model).parent_path().string();
  HR_ASSIGN_OR_RETURN(const ProcessResult run, RunProcess(SimulateArgv(request), options));
  if (run.exit_code != 0)
    return FailedPrecondition("hairrig simulate " + request.model + ": " + run.Describe());
  const size_t end = run.out.find_last_not_of('\n');
  const size_t start = end == std::string::npos ? std::string::npos : run.out.rfind('\n', end);
  const std::string last_line =
      end == std::string::npos ? "" : run.out.substr(start == std::string::npos ? 0 : start + 1);
  return ParseJson(last_line, "the summary of hairrig simulate --out " + request.out_dir);
}

}  // namespace hairrig
