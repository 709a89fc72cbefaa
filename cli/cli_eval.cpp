// `hairrig eval <stage> DIR`: a stage's output against the simulated rig's
// ground truth (<capture>/ground_truth/). Stages: calibration, intrinsics, reconstruction.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "calibration/calibration_evaluation.h"
#include "cli/cli.h"
#include "reconstruction/reconstruction_evaluation.h"
#include "rig/calibrate_capture.h"

namespace hairrig {

void AddEvalCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd =
      app.add_subcommand("eval", "Compare a stage's output with the simulated rig's ground truth");
  cmd->require_subcommand(1);
  auto* calibration =
      cmd->add_subcommand("calibration", "errors of DIR/calibration/ per view and camera");
  auto dir = std::make_shared<std::string>();
  calibration->add_option("DIR", *dir, "a calibrated capture of the simulated rig")
      ->required()
      ->check(CLI::ExistingDirectory);
  calibration->add_flag("--json", common.json, "print the summary as one JSON object");
  calibration->callback([dir, &dispatch] {
    DispatchSummary(dispatch, [dir] { return EvaluateCaptureCalibration({.capture_dir = *dir}); });
  });
  auto* intrinsics = cmd->add_subcommand("intrinsics",
                                         "errors of DIR/intrinsics.json (calibrate-intrinsics) "
                                         "against DIR/ground_truth.json (sim charuco)");
  intrinsics->add_option("DIR", *dir, "a folder from `hairrig sim charuco`, calibrated")
      ->required()
      ->check(CLI::ExistingDirectory);
  intrinsics->add_flag("--json", common.json, "print the summary as one JSON object");
  intrinsics->callback([dir, &dispatch] {
    DispatchSummary(dispatch, [dir] { return EvaluateIntrinsicsFolder({.dir = *dir}); });
  });
  auto* reconstruction =
      cmd->add_subcommand("reconstruction",
                          "masks, orientation, depth, points and strands (if any) of "
                          "DIR/reconstruction/ against DIR/ground_truth/");
  auto threads = std::make_shared<int>(2);
  reconstruction->add_option("DIR", *dir, "a reconstructed capture of the simulated rig")
      ->required()
      ->check(CLI::ExistingDirectory);
  reconstruction->add_option("--threads", *threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  reconstruction->add_flag("--json", common.json, "print the summary as one JSON object");
  reconstruction->callback([dir, threads, &dispatch] {
    dispatch.action = [dir, threads]() -> Result<nlohmann::json> {
      ReconstructionEvalOptions options;
      options.threads = *threads;
      HR_ASSIGN_OR_RETURN(const ReconstructionEvaluation evaluation,
                          EvaluateReconstruction(*dir, options));
      nlohmann::json j = evaluation.ToJson();
      j["dir"] = *dir;
      j["brief"] = evaluation.BriefReport();
      return j;
    };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("reconstruction of %s against the ground truth\n%s",
                  j["dir"].get<std::string>().c_str(), j["brief"].get<std::string>().c_str());
    };
  });
}

}  // namespace hairrig
