#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/cli.h"
#include "core/log.h"
#include "rig/capture_and_process.h"

namespace hairrig {
namespace {

// Live one-line display on a terminal; plain log lines otherwise.
std::function<void(const CaptureProgress&)> ProgressPrinter() {
  const bool terminal = ::isatty(STDERR_FILENO) != 0;
  return [terminal](const CaptureProgress& p) {
    char line[256];
    std::snprintf(
        line, sizeof line, "%d of %d views stored | stop %d of %d | %s | ETA %.0f s | faults %d",
        p.views_done, p.views_total, p.stop + 1, p.stops_total, p.step.c_str(), p.eta_s, p.faults);
    if (terminal) {
      std::fprintf(stderr, "\r\033[K%s", line);
      std::fflush(stderr);
    } else if (p.step.rfind("stored", 0) == 0 || p.step.rfind("re-shooting", 0) == 0) {
      LogInfo(line);
    }
  };
}

// Ends the progress line on a terminal.
void EndProgressLine(const CaptureSummary&) {
  if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
}

}  // namespace

void AddCaptureCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "capture", "Run the capture plan (38 views by default) into a new capture folder");
  auto options = std::make_shared<CaptureAndProcessOptions>();
  cmd->add_option("--config", options->config_path,
                  "rig config (default: etc/sim-rig.yaml, the simulated rig)");
  cmd->add_option(
         "--out", options->out_dir,
         "capture folder; must not exist unless --resume (with --subject: the folder of captures)")
      ->required();
  cmd->add_option("--subject", options->subject,
                  "subject or wig name; the capture goes to OUT/<subject>");
  cmd->add_flag("--resume", options->resume,
                "continue an interrupted capture: keep verified frames, shoot the rest");
  cmd->add_flag("--calibrate", options->calibrate,
                "detect the box's tags as frames land and calibrate the capture when it completes "
                "(as `calibrate`)");
  cmd->add_flag("--reconstruct", options->reconstruct,
                "with --calibrate: reconstruct the hair (points, then strands) when the "
                "calibration is not failed, as `reconstruct`");
  cmd->add_option("--intrinsics", options->intrinsics_files,
                  "with --calibrate: intrinsics held, as `calibrate --intrinsics`")
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", options->threads,
                  "with --calibrate: threads for tag detection, calibration and reconstruction")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([options, &dispatch] {
    const Status valid = options->Check();
    if (!valid.ok()) throw CLI::ValidationError("capture", valid.message());
    options->on_progress = ProgressPrinter();
    options->on_captured = EndProgressLine;
    DispatchSummary(dispatch, [options] { return CaptureAndProcess(*options); });
    // 3: the capture ended incomplete or stopped, or its calibration was skipped for lack of room.
    dispatch.exit_code = [](const nlohmann::json& j) {
      return j["status"] == "complete" && !j.contains("calibration_skipped") ? 0 : 3;
    };
  });
}

}  // namespace hairrig
