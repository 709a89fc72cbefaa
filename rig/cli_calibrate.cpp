#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "calibration/calibration_io.h"
#include "calibration/calibration_report.h"
#include "calibration/charuco_intrinsics.h"
#include "core/charuco_board.h"
#include "core/file_util.h"
#include "core/geometry_json.h"
#include "rig/capture_calibration_input.h"
#include "rig/cli.h"

namespace hairrig {
namespace {

struct CalibrateArgs {
  std::string dir;
  std::string mode = "turntable";
  std::vector<std::string> priors;  // files whose intrinsics are held fixed
  bool hard_prior = false;
  int threads = 2;
};

}  // namespace

namespace {

// Each held camera's prior against the views alone (calibration/prior_check.h).
nlohmann::json PriorChecksJson(const CalibratedFolder& done) {
  nlohmann::json checks = nlohmann::json::array();
  for (size_t c = 0; c < done.result.cameras.size(); ++c) {
    const PriorCheck& check = done.result.cameras[c].prior_check;
    if (!check.tested && check.not_tested.empty()) continue;
    nlohmann::json j{{"serial", done.input.cameras[c].serial},
                     {"file", done.input.cameras[c].prior_source},
                     {"tested", check.tested},
                     {"rejected", check.rejected},
                     {"summary", DescribePriorCheck(check)}};
    if (check.tested) {
      j["chi2"] = check.chi2;
      j["dof"] = check.dof;
      j["sigma"] = check.sigma;
    }
    checks.push_back(std::move(j));
  }
  return checks;
}

}  // namespace

nlohmann::json CalibrationSummaryJson(const CalibratedFolder& done) {
  int solved = 0;
  for (const FrameCalibration& f : done.result.frames) solved += f.solved;
  return nlohmann::json{{"dir", done.out_dir},
                        {"mode", done.result.mode == CalibrationMode::kFree ? "free" : "turntable"},
                        {"verdict", done.verdict.name()},
                        {"reasons", done.verdict.reasons},
                        {"views", done.result.frames.size()},
                        {"views_solved", solved},
                        {"rms_px", done.result.rms_px},
                        {"converged", done.result.converged},
                        {"detect_s", done.result.detect_s},
                        {"init_s", done.result.init_s},
                        {"solve_s", done.result.solve_s},
                        {"prior_checks", PriorChecksJson(done)},
                        {"prior_check_s", done.result.prior_check_s},
                        {"write_s", done.write_s},
                        {"report_s", done.report_s},
                        {"report", done.out_dir + "/report/report.txt"}};
}

void PrintCalibrationSummary(const nlohmann::json& j) {
  std::printf("calibration %s (%s mode): %s\n", j["dir"].get<std::string>().c_str(), j["mode"].get<std::string>().c_str(),
              j["verdict"].get<std::string>().c_str());
  for (const auto& reason : j["reasons"]) std::printf("  - %s\n", reason.get<std::string>().c_str());
  std::printf("  %d of %d views solved, RMS %.3f px; detection %.2f s, initialisation %.2f s, bundle adjustment %.2f s, "
              "writing %.2f s + report %.2f s\n",
              j["views_solved"].get<int>(), j["views"].get<int>(), j["rms_px"].get<double>(), j["detect_s"].get<double>(),
              j["init_s"].get<double>(), j["solve_s"].get<double>(), j["write_s"].get<double>(), j["report_s"].get<double>());
  std::printf("  report: %s\n", j["report"].get<std::string>().c_str());
}

namespace {

Result<nlohmann::json> RunCalibrate(const CalibrateArgs& a) {
  CalibrateFolderOptions options;
  options.calibration.mode = a.mode == "free" ? CalibrationMode::kFree : CalibrationMode::kTurntable;
  options.calibration.threads = a.threads;
  options.calibration.hard_prior = a.hard_prior;
  options.prior_files = a.priors;
  HR_ASSIGN_OR_RETURN(CalibratedFolder done, CalibrateCaptureFolder(a.dir, options));
  return CalibrationSummaryJson(done);
}

struct IntrinsicsArgs {
  std::string dir;
  std::string board;
  std::string serial;
  std::string out;  // default DIR/intrinsics.json
  bool free_k3 = false;
  int threads = 2;
  std::string mrcal_corners;  // also write the corners for mrcal-calibrate-cameras
};

// The used images' corners as mrcal's corners cache (vnl: filename x y level,
// object_width_n points per row, rows in order, "-" for a corner not found).
Status WriteMrcalCorners(const std::string& path, const ChArUcoBoard& board, const ChArUcoCalibration& result) {
  std::string text = "# filename x y level\n";
  const size_t grid = board.corners_board_mm.size();
  for (const ChArUcoImage& image : result.images) {
    if (!image.used) continue;
    std::vector<const Eigen::Vector2d*> at(grid, nullptr);
    for (size_t k = 0; k < image.detected.ids.size(); ++k)
      at[static_cast<size_t>(image.detected.ids[k])] = &image.detected.corners_px[k];
    for (const Eigen::Vector2d* c : at) {
      char line[64];
      if (c)
        std::snprintf(line, sizeof line, " %.4f %.4f 0\n", c->x(), c->y());
      else
        std::snprintf(line, sizeof line, " - - -\n");
      text += std::filesystem::path(image.path).filename().string() + line;
    }
  }
  return WriteFileAtomic(path, text);
}

// The images of a folder, by name: .png, .jpg, .jpeg, .tif, .tiff.
std::vector<std::string> ImagesIn(const std::string& dir) {
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff"))
      paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

Result<nlohmann::json> RunCalibrateIntrinsics(const IntrinsicsArgs& a) {
  HR_ASSIGN_OR_RETURN(ChArUcoBoard board, LoadChArUcoBoard(a.board));
  const std::vector<std::string> images = ImagesIn(a.dir);
  if (images.empty())
    return InvalidArgument(a.dir + ": no images (.png, .jpg, .tif) of the ChArUco board in this folder");
  ChArUcoCalibrationOptions options;
  options.fix_k3 = !a.free_k3;
  options.threads = a.threads;
  HR_ASSIGN_OR_RETURN(ChArUcoCalibration result, CalibrateIntrinsicsFromChArUco(images, board, options));
  const std::string out = a.out.empty() ? (std::filesystem::path(a.dir) / "intrinsics.json").string() : a.out;
  HR_RETURN_IF_ERROR(WriteIntrinsicsFile(out, a.serial, a.board, result));
  if (!a.mrcal_corners.empty()) HR_RETURN_IF_ERROR(WriteMrcalCorners(a.mrcal_corners, board, result));
  nlohmann::json j{{"out", out},
                   {"serial", a.serial},
                   {"images", images.size()},
                   {"images_used", result.images_used},
                   {"rms_px", result.rms_px},
                   {"intrinsics", IntrinsicsToJson(result.intrinsics)},
                   {"left_out", nlohmann::json::array()}};
  for (size_t k = 0; k < result.stddev.size(); ++k)
    j["intrinsics_stddev"][CameraIntrinsics::kParamNames[k]] = result.stddev[k];
  for (const ChArUcoImage& image : result.images)
    if (!image.used) j["left_out"].push_back(image.path + ": " + image.failure);
  return j;
}

void PrintCalibrateIntrinsics(const nlohmann::json& j) {
  const auto& k = j["intrinsics"];
  const auto& sd = j["intrinsics_stddev"];
  std::printf("intrinsics of %s from %d of %d images, RMS %.3f px -> %s\n", j["serial"].get<std::string>().c_str(),
              j["images_used"].get<int>(), j["images"].get<int>(), j["rms_px"].get<double>(),
              j["out"].get<std::string>().c_str());
  for (const char* name : {"fx_px", "fy_px", "cx_px", "cy_px"})
    std::printf("  %-6s %10.3f +- %.3f\n", name, k[name].get<double>(), sd[name].get<double>());
  for (const char* name : {"k1", "k2", "p1", "p2", "k3"})
    std::printf("  %-6s %10.6f +- %.6f\n", name, k[name].get<double>(), sd[name].get<double>());
  for (const auto& line : j["left_out"]) std::printf("  left out: %s\n", line.get<std::string>().c_str());
  std::printf("  use it: hairrig calibrate CAPTURE --intrinsics %s [--intrinsics OTHER_CAMERA.json]\n",
              j["out"].get<std::string>().c_str());
}

void AddCalibrateIntrinsicsCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("calibrate-intrinsics",
                                 "One camera's intrinsics from images of a ChArUco board (writes DIR/intrinsics.json)");
  auto args = std::make_shared<IntrinsicsArgs>();
  cmd->add_option("DIR", args->dir, "a folder of the camera's images of the board")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--board", args->board, "the ChArUco board file (e.g. etc/charuco-board.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--serial", args->serial, "the camera's serial, as in the rig config")->required();
  cmd->add_option("--out", args->out, "output file (default DIR/intrinsics.json)");
  cmd->add_flag("--free-k3", args->free_k3, "solve k3 too (wide-angle lenses; needs views up to the image corners)");
  cmd->add_option("--threads", args->threads, "detection threads")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--mrcal-corners", args->mrcal_corners,
                  "also write the used images' corners as mrcal's corners cache (for mrcal-calibrate-cameras)");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunCalibrateIntrinsics(*args); };
    dispatch.print_human = PrintCalibrateIntrinsics;
  });
}

}  // namespace

void AddCalibrateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("calibrate", "Solve every view's camera from the AprilTag box (writes DIR/calibration/)");
  auto args = std::make_shared<CalibrateArgs>();
  cmd->add_option("DIR", args->dir, "a capture folder made by `hairrig capture`")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--mode", args->mode, "turntable: cameras fixed, box turning (default); free: a pose per view")
      ->check(CLI::IsMember({"turntable", "free"}));
  cmd->add_option("--intrinsics", args->priors,
                  "intrinsics held fixed, matched by camera serial: files from `calibrate-intrinsics` (one per "
                  "camera) or a calibration.json; repeat for several")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--hard-prior", args->hard_prior,
                "hold the --intrinsics exactly instead of by a Gaussian prior with their standard deviations "
                "(then their uncertainty is missing from the poses')");
  cmd->add_option("--threads", args->threads, "detection and solver threads")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunCalibrate(*args); };
    dispatch.print_human = PrintCalibrationSummary;
    dispatch.exit_code = [](const nlohmann::json& j) { return j["verdict"] == "failed" ? 3 : 0; };
  });
  AddCalibrateIntrinsicsCommand(app, common, dispatch);
}

}  // namespace hairrig
