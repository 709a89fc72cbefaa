#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "calibration/calibration_io.h"
#include "calibration/calibration_report.h"
#include "rig/capture_calibration_input.h"
#include "rig/cli.h"

namespace hairrig {
namespace {

struct CalibrateArgs {
  std::string dir;
  std::string mode = "turntable";
  std::string prior;  // calibration.json whose intrinsics are held fixed
  int threads = 2;
};

// Holds every camera at the intrinsics a prior calibration gives for its serial.
Status ApplyPrior(const std::string& prior_path, CaptureCalibrationInput* input) {
  HR_ASSIGN_OR_RETURN(StoredCalibration prior, ReadCalibration(prior_path));
  for (CalibrationCamera& camera : input->cameras) {
    const StoredCalibration::Camera* match = nullptr;
    for (const StoredCalibration::Camera& c : prior.cameras)
      if (c.serial == camera.serial && c.solved) match = &c;
    if (!match) return InvalidArgument("--intrinsics " + prior_path + " has no solved camera with serial " + camera.serial);
    if (match->intrinsics.width_px != camera.width_px || match->intrinsics.height_px != camera.height_px)
      return InvalidArgument("--intrinsics " + prior_path + ": camera " + camera.serial + " was calibrated at " +
                             std::to_string(match->intrinsics.width_px) + " x " +
                             std::to_string(match->intrinsics.height_px) + " px, the capture's frames are " +
                             std::to_string(camera.width_px) + " x " + std::to_string(camera.height_px));
    camera.nominal = match->intrinsics;
  }
  return Status::Ok();
}

Result<nlohmann::json> RunCalibrate(const CalibrateArgs& a) {
  HR_ASSIGN_OR_RETURN(CaptureCalibrationInput input, LoadCaptureCalibrationInput(a.dir));
  CaptureCalibrationOptions options;
  options.mode = a.mode == "free" ? CalibrationMode::kFree : CalibrationMode::kTurntable;
  options.threads = a.threads;
  if (!a.prior.empty()) {
    HR_RETURN_IF_ERROR(ApplyPrior(a.prior, &input));
    options.fix_intrinsics = true;
  }
  HR_ASSIGN_OR_RETURN(CaptureCalibration result, CalibrateCapture(input, options));
  const std::string out_dir = (std::filesystem::path(a.dir) / "calibration").string();
  HR_RETURN_IF_ERROR(WriteCalibration(out_dir, input, result));
  const CalibrationVerdict verdict = JudgeCalibration(input, result);
  HR_RETURN_IF_ERROR(WriteCalibrationReport(out_dir + "/report", input, result, verdict));
  int solved = 0;
  for (const FrameCalibration& f : result.frames) solved += f.solved;
  return nlohmann::json{{"dir", out_dir},
                        {"mode", a.mode},
                        {"verdict", verdict.name()},
                        {"reasons", verdict.reasons},
                        {"views", result.frames.size()},
                        {"views_solved", solved},
                        {"rms_px", result.rms_px},
                        {"converged", result.converged},
                        {"detect_s", result.detect_s},
                        {"init_s", result.init_s},
                        {"solve_s", result.solve_s},
                        {"report", out_dir + "/report/report.txt"}};
}

void PrintCalibrate(const nlohmann::json& j) {
  std::printf("calibration %s (%s mode): %s\n", j["dir"].get<std::string>().c_str(), j["mode"].get<std::string>().c_str(),
              j["verdict"].get<std::string>().c_str());
  for (const auto& reason : j["reasons"]) std::printf("  - %s\n", reason.get<std::string>().c_str());
  std::printf("  %d of %d views solved, RMS %.3f px; detection %.2f s, initialisation %.2f s, bundle adjustment %.2f s\n",
              j["views_solved"].get<int>(), j["views"].get<int>(), j["rms_px"].get<double>(), j["detect_s"].get<double>(),
              j["init_s"].get<double>(), j["solve_s"].get<double>());
  std::printf("  report: %s\n", j["report"].get<std::string>().c_str());
}

}  // namespace

void AddCalibrateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("calibrate", "Solve every view's camera from the AprilTag box (writes DIR/calibration/)");
  auto args = std::make_shared<CalibrateArgs>();
  cmd->add_option("DIR", args->dir, "a capture folder made by `hairrig capture`")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--mode", args->mode, "turntable: cameras fixed, box turning (default); free: a pose per view")
      ->check(CLI::IsMember({"turntable", "free"}));
  cmd->add_option("--intrinsics", args->prior,
                  "a calibration.json whose intrinsics (matched by camera serial) are held fixed")
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", args->threads, "detection and solver threads")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunCalibrate(*args); };
    dispatch.print_human = PrintCalibrate;
    dispatch.exit_code = [](const nlohmann::json& j) { return j["verdict"] == "failed" ? 3 : 0; };
  });
}

}  // namespace hairrig
