#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "core/log.h"
#include "rig/capture.h"
#include "rig/cli.h"
#include "rig/rig_config.h"
#include "rig/safe_names.h"

namespace hairrig {
namespace {

struct CaptureArgs {
  std::string config;
  std::string out;
  std::string subject;
  bool resume = false;
};

// Live one-line display on a terminal; plain log lines otherwise.
std::function<void(const CaptureProgress&)> ProgressPrinter() {
  const bool terminal = ::isatty(STDERR_FILENO) != 0;
  return [terminal](const CaptureProgress& p) {
    char line[256];
    std::snprintf(line, sizeof line, "%d of %d views stored | stop %d of %d | %s | ETA %.0f s | faults %d",
                  p.views_done, p.views_total, p.stop + 1, p.stops_total, p.step.c_str(), p.eta_s, p.faults);
    if (terminal) {
      std::fprintf(stderr, "\r\033[K%s", line);
      std::fflush(stderr);
    } else if (p.step.rfind("stored", 0) == 0 || p.step.rfind("re-shooting", 0) == 0) {
      LogInfo(line);
    }
  };
}

Result<nlohmann::json> RunCaptureCommand(const CaptureArgs& a) {
  CaptureOptions options;
  options.resume = a.resume;
  options.out_dir = a.out;
  if (!a.subject.empty()) {
    HR_ASSIGN_OR_RETURN(std::string folder, SubjectFolderName(a.subject));
    std::error_code ec;
    std::filesystem::create_directories(a.out, ec);
    if (ec) return IoError(a.out + ": cannot create the folder of captures (" + ec.message() + ")");
    options.out_dir = (std::filesystem::path(a.out) / folder).string();
    options.subject = a.subject;
  }
  options.config_path = a.config;
  if (options.config_path.empty() && !a.resume) {
    HR_ASSIGN_OR_RETURN(options.config_path, DefaultRigConfigPath());
  }
  if (a.resume && !a.config.empty()) {
    LogWarning("--config is ignored with --resume: the capture's own rig.yaml snapshot is used");
  }
  options.on_progress = ProgressPrinter();
  HR_ASSIGN_OR_RETURN(CaptureSummary summary, RunCapture(options));
  if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
  return summary.ToJson();
}

void PrintCaptureSummary(const nlohmann::json& j) {
  std::printf("capture %s: %s\n", j["dir"].get<std::string>().c_str(), j["status"].get<std::string>().c_str());
  std::printf("  views %d of %d (%d kept from before), %d frames, %.1f MB stored, %d faults\n",
              j["views_completed"].get<int>(), j["views_planned"].get<int>(), j["views_kept"].get<int>(),
              j["frames"].get<int>(), j["bytes"].get<double>() / 1e6, j["faults"].get<int>());
  std::printf("  sweep %.2f s, physical lower bound %.2f s, efficiency %.3f (setup %.2f s)\n", j["wall_s"].get<double>(),
              j["lower_bound_s"].get<double>(), j["efficiency"].get<double>(), j["setup_s"].get<double>());
  if (!j["message"].get<std::string>().empty()) std::printf("  %s\n", j["message"].get<std::string>().c_str());
}

}  // namespace

void AddCaptureCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("capture", "Run the capture plan (38 views by default) into a new capture folder");
  auto args = std::make_shared<CaptureArgs>();
  cmd->add_option("--config", args->config, "rig config (default: etc/sim-rig.yaml, the simulated rig)");
  cmd->add_option("--out", args->out, "capture folder; must not exist unless --resume (with --subject: the folder of captures)")
      ->required();
  cmd->add_option("--subject", args->subject, "subject or wig name; the capture goes to OUT/<subject>");
  cmd->add_flag("--resume", args->resume, "continue an interrupted capture: keep verified frames, shoot the rest");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunCaptureCommand(*args); };
    dispatch.print_human = PrintCaptureSummary;
    dispatch.exit_code = [](const nlohmann::json& j) { return j["status"] == "complete" ? 0 : 3; };
  });
}

}  // namespace hairrig
