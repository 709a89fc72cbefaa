// `hairrig eval <stage> DIR`: a stage's output against the simulated rig's
// ground truth (<capture>/ground_truth/). Stages: calibration.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <CLI/CLI.hpp>

#include "calibration/calibration_io.h"
#include "core/geometry_json.h"
#include "core/json_file.h"
#include "rig/cli.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

struct TruthView {
  std::string serial;
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_box;
};

Result<std::map<int, TruthView>> ReadGroundTruthViews(const std::string& capture_dir) {
  const std::string path = (fs::path(capture_dir) / "ground_truth" / "ground_truth.json").string();
  HR_ASSIGN_OR_RETURN(nlohmann::json root,
                      ReadJsonFile(path, "only captures from the simulated rig have a ground truth"));
  if (!root.contains("views") || !root["views"].is_array()) return CorruptData(path + ": views is not an array");
  std::map<int, TruthView> views;
  for (size_t i = 0; i < root["views"].size(); ++i) {
    const nlohmann::json& j = root["views"][i];
    const std::string where = path + ": views[" + std::to_string(i) + "]";
    if (!j.contains("view") || !j["view"].is_number_integer()) return CorruptData(where + ": view is not an integer");
    TruthView v;
    v.serial = j.value("camera_serial", "");
    auto intrinsics = IntrinsicsFromJson(j.value("intrinsics", nlohmann::json()), where + ".intrinsics");
    auto pose = PoseFromJson(j.value("cam_from_box", nlohmann::json()), where + ".cam_from_box");
    if (!intrinsics.ok()) return CorruptData(intrinsics.status().message());
    if (!pose.ok()) return CorruptData(pose.status().message());
    v.intrinsics = *intrinsics;
    v.cam_from_box = *pose;
    views[j["view"].get<int>()] = v;
  }
  return views;
}

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

Result<nlohmann::json> EvalCalibration(const std::string& dir) {
  HR_ASSIGN_OR_RETURN(StoredCalibration calibration,
                      ReadCalibration((fs::path(dir) / "calibration" / "calibration.json").string()));
  HR_ASSIGN_OR_RETURN(auto truth, ReadGroundTruthViews(dir));
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
}

}  // namespace hairrig
