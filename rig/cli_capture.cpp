#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "calibration/tag_detection_sink.h"
#include "core/log.h"
#include "core/clock.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture.h"
#include "rig/cli.h"
#include "rig/reconstruct_capture.h"
#include "rig/rig_config.h"
#include "rig/safe_names.h"

namespace hairrig {
namespace {

struct CaptureArgs {
  std::string config;
  std::string out;
  std::string subject;
  bool resume = false;
  bool calibrate = false;
  bool reconstruct = false;
  std::vector<std::string> priors;  // --intrinsics for the calibration
};

// With --calibrate: tags are detected as the frames land, and the capture is
// calibrated when it completes; the delay from the last frame is reported.
Result<nlohmann::json> CalibrateAfterCapture(const std::string& dir, const std::vector<std::string>& priors,
                                             TagDetectionSink& sink) {
  const double capture_closed_s = static_cast<double>(SteadyNowNs() - sink.last_frame_ns()) * 1e-9;
  const std::map<std::string, ViewObservations> detected = sink.WaitForAll();
  const double detection_backlog_s = static_cast<double>(sink.last_detected_ns() - sink.last_frame_ns()) * 1e-9;
  CalibrateFolderOptions options;
  options.prior_files = priors;
  options.detected = &detected;
  int64_t written_ns = 0;
  options.on_written = [&] { written_ns = SteadyNowNs(); };
  HR_ASSIGN_OR_RETURN(CalibratedFolder done, CalibrateCaptureFolder(dir, options));
  nlohmann::json summary = CalibrationSummaryJson(done);
  summary["frames_detected_during_capture"] = detected.size();
  summary["detection_backlog_s"] = detection_backlog_s;
  summary["capture_closed_s"] = capture_closed_s;
  summary["calibration_after_last_frame_s"] = static_cast<double>(written_ns - sink.last_frame_ns()) * 1e-9;
  summary["delay_after_last_frame_s"] = static_cast<double>(SteadyNowNs() - sink.last_frame_ns()) * 1e-9;
  return summary;
}

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
  std::unique_ptr<TagDetectionSink> sink;
  if (a.calibrate) {
    HR_ASSIGN_OR_RETURN(RigConfig config,
                        a.resume ? LoadCaptureRigConfig(options.out_dir) : LoadRigConfig(options.config_path));
    HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
    sink = std::make_unique<TagDetectionSink>(section.box, TagDetectorOptions{}, 2);
    options.sink = sink.get();
  }
  HR_ASSIGN_OR_RETURN(CaptureSummary summary, RunCapture(options));
  if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
  nlohmann::json out = summary.ToJson();
  if (sink && out["status"] == "complete") {
    HR_ASSIGN_OR_RETURN(out["calibration"], CalibrateAfterCapture(options.out_dir, a.priors, *sink));
    if (a.reconstruct && out["calibration"]["verdict"] != "failed") {
      ReconstructCaptureOptions reconstruct;
      reconstruct.dir = options.out_dir;
      HR_ASSIGN_OR_RETURN(const ReconstructCaptureSummary reconstruction, ReconstructCapture(reconstruct));
      out["reconstruction"] = reconstruction.ToJson();
    }
  }
  return out;
}

void PrintCaptureSummary(const nlohmann::json& j) {
  std::printf("capture %s: %s\n", j["dir"].get<std::string>().c_str(), j["status"].get<std::string>().c_str());
  std::printf("  views %d of %d (%d kept from before), %d frames, %.1f MB stored, %d faults\n",
              j["views_completed"].get<int>(), j["views_planned"].get<int>(), j["views_kept"].get<int>(),
              j["frames"].get<int>(), j["bytes"].get<double>() / 1e6, j["faults"].get<int>());
  std::printf("  sweep %.2f s, physical lower bound %.2f s, efficiency %.3f (setup %.2f s)\n", j["wall_s"].get<double>(),
              j["lower_bound_s"].get<double>(), j["efficiency"].get<double>(), j["setup_s"].get<double>());
  if (!j["message"].get<std::string>().empty()) std::printf("  %s\n", j["message"].get<std::string>().c_str());
  if (j.contains("calibration")) {
    PrintCalibrationSummary(j["calibration"]);
    std::printf("  after the last frame: its detection done %.2f s, capture closed (contact sheet, ground truth) "
                "%.2f s, calibration.json written %.2f s, report %.2f s (%d frames detected during the capture)\n",
                j["calibration"]["detection_backlog_s"].get<double>(), j["calibration"]["capture_closed_s"].get<double>(),
                j["calibration"]["calibration_after_last_frame_s"].get<double>(),
                j["calibration"]["delay_after_last_frame_s"].get<double>(),
                j["calibration"]["frames_detected_during_capture"].get<int>());
  }
  if (j.contains("reconstruction")) std::printf("%s", j["reconstruction"]["brief"].get<std::string>().c_str());
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
  cmd->add_flag("--calibrate", args->calibrate,
                "detect the box's tags as frames land and calibrate the capture when it completes (as `calibrate`)");
  cmd->add_flag("--reconstruct", args->reconstruct,
                "with --calibrate: reconstruct the hair (points, then strands) when the calibration is not failed, "
                "as `reconstruct`");
  cmd->add_option("--intrinsics", args->priors, "with --calibrate: intrinsics held, as `calibrate --intrinsics`")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    if (!args->priors.empty() && !args->calibrate) throw CLI::ValidationError("capture", "--intrinsics needs --calibrate");
    if (args->reconstruct && !args->calibrate) throw CLI::ValidationError("capture", "--reconstruct needs --calibrate");
    dispatch.action = [args] { return RunCaptureCommand(*args); };
    dispatch.print_human = PrintCaptureSummary;
    dispatch.exit_code = [](const nlohmann::json& j) { return j["status"] == "complete" ? 0 : 3; };
  });
}

}  // namespace hairrig
