#include <CLI/CLI.hpp>

#include "calibration/intrinsics_folder.h"
#include "cli/cli.h"
#include "rig/calibrate_capture.h"

namespace hairrig {
namespace {

struct CalibrateArgs {
  std::string dir;
  std::string mode = "turntable";
  bool exact_box = false;
  CalibrateFolderOptions options;
};

void AddCalibrateBoxCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "calibrate-box",
      "Refine the calibration box as built from several captures of it, in turn (writes --out)");
  auto options = std::make_shared<RefineBoxOptions>();
  cmd->add_option("DIR", options->capture_dirs, "capture folders made by `hairrig capture`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", options->out_file, "the box file to write (box_as_built.yaml)")
      ->required();
  cmd->add_option("--box", options->box_file,
                  "the box to start from (default: the first capture's rig config's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--intrinsics", options->prior_files,
                  "intrinsics held, matched by camera serial, as for `calibrate`")
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", options->calibration.threads, "detection and solver threads")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([options, &dispatch] {
    DispatchSummary(dispatch, [options] { return RefineBoxFromCaptures(*options); });
  });
}

void AddCalibrateIntrinsicsCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "calibrate-intrinsics",
      "One camera's intrinsics from images of a ChArUco board (writes DIR/intrinsics.json)");
  auto options = std::make_shared<IntrinsicsFolderOptions>();
  cmd->add_option("DIR", options->images_dir, "a folder of the camera's images of the board")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--board", options->board_file,
                  "the ChArUco board file (e.g. etc/charuco-board.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--serial", options->serial, "the camera's serial, as in the rig config")
      ->required();
  cmd->add_option("--out", options->out_file, "output file (default DIR/intrinsics.json)");
  cmd->add_flag("!--free-k3", options->calibration.fix_k3,
                "solve k3 too (wide-angle lenses; needs views up to the image corners)");
  cmd->add_option("--threads", options->calibration.threads, "detection threads")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option(
      "--mrcal-corners", options->mrcal_corners_file,
      "also write the used images' corners as mrcal's corners cache (for mrcal-calibrate-cameras)");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([options, &dispatch] {
    DispatchSummary(dispatch, [options] { return CalibrateIntrinsicsFolder(*options); });
  });
}

}  // namespace

void AddCalibrateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "calibrate", "Solve every view's camera from the AprilTag box (writes DIR/calibration/)");
  auto args = std::make_shared<CalibrateArgs>();
  cmd->add_option("DIR", args->dir, "a capture folder made by `hairrig capture`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--mode", args->mode,
                  "turntable: cameras fixed, box turning (default); free: a pose per view")
      ->check(CLI::IsMember({"turntable", "free"}));
  cmd->add_option("--intrinsics", args->options.prior_files,
                  "intrinsics held fixed, matched by camera serial: files from "
                  "`calibrate-intrinsics` (one per camera) or a calibration.json; repeat for "
                  "several")
      ->check(CLI::ExistingFile);
  cmd->add_flag(
      "--hard-prior", args->options.calibration.hard_prior,
      "hold the --intrinsics exactly instead of by a Gaussian prior with their standard deviations "
      "(then their uncertainty is missing from the poses')");
  cmd->add_option("--box", args->options.box_file,
                  "the calibration box to solve against, in place of the rig config's: a "
                  "box_as_built.yaml an earlier calibration wrote, or a drawn box")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--exact-box", args->exact_box,
                "take the box as exact instead of refining its tags and faces with the cameras");
  cmd->add_option("--threads", args->options.calibration.threads, "detection and solver threads")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    if (args->exact_box) args->options.calibration.box_tolerance = BoxTolerance{};
    args->options.calibration.mode =
        args->mode == "free" ? CalibrationMode::kFree : CalibrationMode::kTurntable;
    DispatchSummary(dispatch, [args] { return CalibrateCaptureFolder(args->dir, args->options); });
    dispatch.exit_code = FailedVerdictExitCode;
  });
  AddCalibrateIntrinsicsCommand(app, common, dispatch);
  AddCalibrateBoxCommand(app, common, dispatch);
}

}  // namespace hairrig
