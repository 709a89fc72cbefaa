// `hairrig eval <stage> DIR`: a stage's output against the simulated rig's
// ground truth (<capture>/ground_truth/). Stages: calibration, intrinsics, reconstruction.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>

#include "calibration/calibration_io.h"
#include "calibration/uncertainty_check.h"
#include "core/geometry_json.h"
#include "core/json_file.h"
#include "core/truth_maps.h"
#include "reconstruction/reconstruction_evaluation.h"
#include "rig/capture_calibration_input.h"
#include "rig/cli.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

using TruthView = CaptureTruth::View;

struct Spread {
  std::vector<double> values;
  nlohmann::json ToJson() const {
    if (values.empty()) return {{"median", nullptr}, {"max", nullptr}};
    std::vector<double> v = values;
    std::sort(v.begin(), v.end());
    return {{"median", v[v.size() / 2]}, {"max", v.back()}};
  }
};

// Errors of one set of poses and intrinsics (the bundle adjustment's, or the initial OpenCV-only ones).
nlohmann::json PoseErrors(const StoredCalibration& calibration, const std::map<int, TruthView>& truth, bool initial,
                          int* compared) {
  Spread rotation, centre, focal, principal;
  std::map<int, bool> camera_done;
  *compared = 0;
  for (const StoredCalibration::View& view : calibration.views) {
    const auto t = truth.find(view.view);
    if (!view.solved || t == truth.end()) continue;
    ++*compared;
    const Rigid3d& estimate = initial ? view.cam_from_box_initial : view.cam_from_box;
    rotation.values.push_back(RotationDifferenceDeg(estimate, t->second.cam_from_box));
    centre.values.push_back(
        (estimate.Inverse().translation - t->second.cam_from_box.Inverse().translation).norm());
    if (camera_done[view.camera]) continue;
    camera_done[view.camera] = true;
    const StoredCalibration::Camera& cam = calibration.cameras[static_cast<size_t>(view.camera)];
    const CameraIntrinsics& k = initial ? cam.initial : cam.intrinsics;
    const CameraIntrinsics& k_true = t->second.intrinsics;
    focal.values.push_back(100 * std::max(std::abs(k.fx_px / k_true.fx_px - 1), std::abs(k.fy_px / k_true.fy_px - 1)));
    principal.values.push_back(std::hypot(k.cx_px - k_true.cx_px, k.cy_px - k_true.cy_px));
  }
  return {{"rotation_deg", rotation.ToJson()},
          {"camera_centre_mm", centre.ToJson()},
          {"focal_percent", focal.ToJson()},
          {"principal_point_px", principal.ToJson()}};
}

// Observed errors against the errors the covariance predicts, over the solved views.
nlohmann::json UncertaintyCheck(const StoredCalibration& calibration, const std::map<int, TruthView>& truth) {
  std::vector<UncertaintySample> samples;
  for (const StoredCalibration::View& view : calibration.views) {
    const auto t = truth.find(view.view);
    if (view.solved && t != truth.end())
      samples.push_back(MakeUncertaintySample(view.cam_from_box, t->second.cam_from_box, view.uncertainty));
  }
  const UncertaintyRatios r = ObservedOverPredicted(samples);
  if (r.views == 0) return {{"views", 0}};
  return {{"views", r.views},
          {"rotation_ratio", r.rotation},
          {"centre_ratio", r.centre},
          {"rotation_mahalanobis_ratio", r.rotation_mahalanobis},
          {"centre_mahalanobis_ratio", r.centre_mahalanobis}};
}

// RMS distance (px, per corner) of the used detections from the true
// projections of the box's tag corners: the corner noise of these frames,
// which the reprojection RMS is compared with.
nlohmann::json CornerNoise(const StoredCalibration& calibration, const std::map<int, TruthView>& truth,
                           const CalibBox& box) {
  double sq = 0;
  int corners = 0;
  for (const StoredCalibration::View& view : calibration.views) {
    const auto t = truth.find(view.view);
    if (!view.solved || t == truth.end()) continue;
    for (const StoredCalibration::Tag& tag : view.tags) {
      const BoxTag* model = box.FindTag(tag.id);
      if (model == nullptr) continue;
      for (size_t k = 0; k < 4; ++k, ++corners) {
        const Eigen::Vector2d truth_px = Project(t->second.intrinsics, t->second.cam_from_box * model->corners_box_mm[k]);
        sq += (tag.corners_px[k] - truth_px).squaredNorm();
      }
    }
  }
  if (corners == 0) return nullptr;
  return std::sqrt(sq / corners);
}

Result<nlohmann::json> EvalCalibration(const std::string& dir) {
  HR_ASSIGN_OR_RETURN(StoredCalibration calibration,
                      ReadCalibration((fs::path(dir) / "calibration" / "calibration.json").string()));
  HR_ASSIGN_OR_RETURN(const CaptureTruth capture_truth, ReadCaptureTruth(dir));
  const std::map<int, TruthView>& truth = capture_truth.views;
  int compared = 0, compared_initial = 0;
  nlohmann::json out{{"stage", "calibration"}, {"dir", dir}, {"mode", calibration.mode}};
  out["solved"] = PoseErrors(calibration, truth, false, &compared);
  out["initial"] = PoseErrors(calibration, truth, true, &compared_initial);
  std::string initial_source = "nominal intrinsics";
  for (const auto& c : calibration.cameras)
    if (c.intrinsics_source == "views") initial_source = "OpenCV calibrateCamera + per-view PnP";
  out["initial_source"] = initial_source;
  Spread rms;
  for (const auto& v : calibration.views)
    if (v.solved) rms.values.push_back(v.rms_px);
  out["solved"]["reprojection_rms_px"] = rms.ToJson();
  HR_ASSIGN_OR_RETURN(RigConfig config, LoadCaptureRigConfig(dir));
  HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
  const CalibBox& box = section.box;
  out["corner_noise_px"] = CornerNoise(calibration, truth, box);
  out["overall_rms_px"] = calibration.rms_px;
  if (out["corner_noise_px"].is_number())
    out["rms_over_corner_noise"] = calibration.rms_px / out["corner_noise_px"].get<double>();
  out["uncertainty"] = UncertaintyCheck(calibration, truth);
  out["views_compared"] = compared;
  out["views"] = calibration.views.size();
  if (compared == 0) return FailedPrecondition(dir + ": no solved view has a ground truth to compare with");
  return out;
}

void PrintErrors(const char* title, const nlohmann::json& e) {
  auto row = [&](const char* name, const char* key, const char* unit) {
    if (!e.contains(key) || e[key]["median"].is_null()) return;
    std::printf("    %-22s median %9.4f  max %9.4f %s\n", name, e[key]["median"].get<double>(), e[key]["max"].get<double>(),
                unit);
  };
  std::printf("  %s\n", title);
  row("rotation", "rotation_deg", "deg");
  row("camera centre", "camera_centre_mm", "mm");
  row("focal length", "focal_percent", "%");
  row("principal point", "principal_point_px", "px");
  row("reprojection RMS", "reprojection_rms_px", "px");
}

void PrintEval(const nlohmann::json& j) {
  std::printf("calibration of %s (%s mode) against the ground truth, %d of %d views\n", j["dir"].get<std::string>().c_str(),
              j["mode"].get<std::string>().c_str(), j["views_compared"].get<int>(), j["views"].get<int>());
  PrintErrors("bundle adjustment:", j["solved"]);
  PrintErrors(("initial (" + j["initial_source"].get<std::string>() + "):").c_str(), j["initial"]);
  if (j.contains("rms_over_corner_noise"))
    std::printf("  reprojection RMS %.4f px against corner noise %.4f px (detections vs truth): %.2fx\n",
                j["overall_rms_px"].get<double>(), j["corner_noise_px"].get<double>(),
                j["rms_over_corner_noise"].get<double>());
  const nlohmann::json& u = j["uncertainty"];
  if (u.value("views", 0) > 0)
    std::printf("  observed / predicted error (1 = the stated uncertainty is right), %d views: rotation %.2f, "
                "centre %.2f (Mahalanobis %.2f, %.2f)\n",
                u["views"].get<int>(), u["rotation_ratio"].get<double>(), u["centre_ratio"].get<double>(),
                u["rotation_mahalanobis_ratio"].get<double>(), u["centre_mahalanobis_ratio"].get<double>());
}

// DIR/intrinsics.json (calibrate-intrinsics) against DIR/ground_truth.json (sim charuco).
Result<nlohmann::json> EvalIntrinsics(const std::string& dir) {
  const std::string truth_path = (fs::path(dir) / "ground_truth.json").string();
  HR_ASSIGN_OR_RETURN(nlohmann::json truth,
                      ReadJsonFile(truth_path, "only image sets from `hairrig sim charuco` have a ground truth"));
  const JsonObject fields(truth, truth_path);
  if (fields.StringOr("format", "") != "hairrig-charuco-truth" || !fields.ok())
    return CorruptData(truth_path + ": not a ChArUco ground truth (format hairrig-charuco-truth)");
  const CameraIntrinsics k_true = IntrinsicsField(fields, "intrinsics");
  HR_RETURN_IF_ERROR(fields.status());
  const std::string solved_path = (fs::path(dir) / "intrinsics.json").string();
  HR_ASSIGN_OR_RETURN(std::vector<IntrinsicsPrior> solved, ReadIntrinsicsPriors(solved_path));
  if (solved.size() != 1) return CorruptData(solved_path + ": not the result of `hairrig calibrate-intrinsics`");
  const auto t = k_true.ToParams(), e = solved[0].intrinsics.ToParams();
  nlohmann::json params;
  double worst_sigma = 0;
  for (size_t p = 0; p < t.size(); ++p) {
    const double sd = solved[0].stddev[p];
    const double sigmas = sd > 0 ? (e[p] - t[p]) / sd : 0;
    worst_sigma = std::max(worst_sigma, std::abs(sigmas));
    params[CameraIntrinsics::kParamNames[p]] = {{"truth", t[p]}, {"solved", e[p]}, {"error", e[p] - t[p]},
                                                {"stddev", sd}, {"error_in_stddev", sigmas}};
  }
  return nlohmann::json{{"stage", "intrinsics"},
                        {"dir", dir},
                        {"serial", solved[0].serial},
                        {"focal_percent", 100 * std::max(std::abs(e[0] / t[0] - 1), std::abs(e[1] / t[1] - 1))},
                        {"principal_point_px", std::hypot(e[2] - t[2], e[3] - t[3])},
                        {"worst_error_in_stddev", worst_sigma},
                        {"params", params}};
}

void PrintEvalIntrinsics(const nlohmann::json& j) {
  std::printf("intrinsics of %s in %s against the ground truth: focal %.4f %%, principal point %.3f px, worst "
              "parameter %.2f sd off\n",
              j["serial"].get<std::string>().c_str(), j["dir"].get<std::string>().c_str(),
              j["focal_percent"].get<double>(), j["principal_point_px"].get<double>(),
              j["worst_error_in_stddev"].get<double>());
  for (const auto& [name, p] : j["params"].items())
    std::printf("  %-6s truth %12.6f solved %12.6f error %+10.3g (%+.2f sd)\n", name.c_str(), p["truth"].get<double>(),
                p["solved"].get<double>(), p["error"].get<double>(), p["error_in_stddev"].get<double>());
}

}  // namespace

void AddEvalCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("eval", "Compare a stage's output with the simulated rig's ground truth");
  cmd->require_subcommand(1);
  auto* calibration = cmd->add_subcommand("calibration", "errors of DIR/calibration/ per view and camera");
  auto dir = std::make_shared<std::string>();
  calibration->add_option("DIR", *dir, "a calibrated capture of the simulated rig")->required()->check(CLI::ExistingDirectory);
  calibration->add_flag("--json", common.json, "print the summary as one JSON object");
  calibration->callback([dir, &dispatch] {
    dispatch.action = [dir] { return EvalCalibration(*dir); };
    dispatch.print_human = PrintEval;
  });
  auto* intrinsics = cmd->add_subcommand("intrinsics", "errors of DIR/intrinsics.json (calibrate-intrinsics) "
                                                       "against DIR/ground_truth.json (sim charuco)");
  intrinsics->add_option("DIR", *dir, "a folder from `hairrig sim charuco`, calibrated")
      ->required()
      ->check(CLI::ExistingDirectory);
  intrinsics->add_flag("--json", common.json, "print the summary as one JSON object");
  intrinsics->callback([dir, &dispatch] {
    dispatch.action = [dir] { return EvalIntrinsics(*dir); };
    dispatch.print_human = PrintEvalIntrinsics;
  });
  auto* reconstruction = cmd->add_subcommand(
      "reconstruction",
      "masks, orientation, depth, points and strands (if any) of DIR/reconstruction/ against DIR/ground_truth/");
  auto threads = std::make_shared<int>(2);
  reconstruction->add_option("DIR", *dir, "a reconstructed capture of the simulated rig")
      ->required()
      ->check(CLI::ExistingDirectory);
  reconstruction->add_option("--threads", *threads, "worker threads")->check(CLI::PositiveNumber)->capture_default_str();
  reconstruction->add_flag("--json", common.json, "print the summary as one JSON object");
  reconstruction->callback([dir, threads, &dispatch] {
    dispatch.action = [dir, threads]() -> Result<nlohmann::json> {
      ReconstructionEvalOptions options;
      options.threads = *threads;
      HR_ASSIGN_OR_RETURN(const ReconstructionEvaluation evaluation, EvaluateReconstruction(*dir, options));
      nlohmann::json j = evaluation.ToJson();
      j["dir"] = *dir;
      j["brief"] = evaluation.BriefReport();
      return j;
    };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("reconstruction of %s against the ground truth\n%s", j["dir"].get<std::string>().c_str(),
                  j["brief"].get<std::string>().c_str());
    };
  });
}

}  // namespace hairrig
