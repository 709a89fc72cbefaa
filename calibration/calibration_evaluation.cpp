#include "calibration/calibration_evaluation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "core/geometry_json.h"
#include "core/json_file.h"
#include "core/statistics.h"
#include "core/string_format.h"

namespace hairrig {

namespace {

using TruthViews = std::map<int, CaptureTruth::View>;

double FocalPercent(const CameraIntrinsics& k, const CameraIntrinsics& k_true) {
  return 100 * std::max(std::abs(k.fx_px / k_true.fx_px - 1), std::abs(k.fy_px / k_true.fy_px - 1));
}

double PrincipalPointPx(const CameraIntrinsics& k, const CameraIntrinsics& k_true) {
  return std::hypot(k.cx_px - k_true.cx_px, k.cy_px - k_true.cy_px);
}

// The solved views that have a true pose, with it.
std::vector<std::pair<const StoredCalibration::View*, const CaptureTruth::View*>> ComparedViews(
    const StoredCalibration& calibration, const TruthViews& truth) {
  std::vector<std::pair<const StoredCalibration::View*, const CaptureTruth::View*>> compared;
  for (const StoredCalibration::View& view : calibration.views) {
    const auto t = truth.find(view.view);
    if (view.solved && t != truth.end()) compared.emplace_back(&view, &t->second);
  }
  return compared;
}

// The ids of the tags the solved views' detections saw.
std::vector<int> TagIdsUsed(const StoredCalibration& calibration) {
  std::vector<int> ids;
  for (const StoredCalibration::View& view : calibration.views)
    if (view.solved)
      for (const StoredCalibration::Tag& tag : view.tags) ids.push_back(tag.id);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

// Whether a tag of `a` (one of `ids`; any, when empty) is also in `b`.
bool SharesATag(const CalibBox& a, const CalibBox& b, const std::vector<int>& ids) {
  return std::any_of(a.tags.begin(), a.tags.end(), [&](const BoxTag& tag) {
    const bool chosen = ids.empty() || std::find(ids.begin(), ids.end(), tag.id) != ids.end();
    return chosen && b.FindTag(tag.id) != nullptr;
  });
}

// `calibration` with its views' cam_from_box (solved and initial) moved from
// its box frame to the true one; the other poses are not compared and stay.
// The stated uncertainties stay as they are: the frames differ by a small
// rotation (box_alignment_deg: 0.08 deg for etc/scenes/hand_built_box.yaml).
StoredCalibration InTrueBoxFrame(StoredCalibration calibration,
                                 const Rigid3d& truth_from_estimated) {
  const Rigid3d estimated_from_truth = truth_from_estimated.Inverse();
  for (StoredCalibration::View& view : calibration.views) {
    view.cam_from_box = view.cam_from_box * estimated_from_truth;
    view.cam_from_box_initial = view.cam_from_box_initial * estimated_from_truth;
  }
  return calibration;
}

// Intrinsics are compared once per camera, at its first compared view.
PoseErrors ComparePoses(const StoredCalibration& calibration, const TruthViews& truth,
                        bool initial) {
  PoseErrors errors;
  std::map<int, bool> camera_done;
  for (const auto& [view, t] : ComparedViews(calibration, truth)) {
    const Rigid3d& estimate = initial ? view->cam_from_box_initial : view->cam_from_box;
    errors.rotation_deg.values.push_back(RotationDifferenceDeg(estimate, t->cam_from_box));
    errors.camera_centre_mm.values.push_back(
        (estimate.Inverse().translation - t->cam_from_box.Inverse().translation).norm());
    if (camera_done[view->camera]) continue;
    camera_done[view->camera] = true;
    const StoredCalibration::Camera& camera =
        calibration.cameras[static_cast<size_t>(view->camera)];
    const CameraIntrinsics& k = initial ? camera.initial : camera.intrinsics;
    errors.focal_percent.values.push_back(FocalPercent(k, t->intrinsics));
    errors.principal_point_px.values.push_back(PrincipalPointPx(k, t->intrinsics));
  }
  return errors;
}

UncertaintyRatios CompareUncertainty(const StoredCalibration& calibration,
                                     const TruthViews& truth) {
  std::vector<UncertaintySample> samples;
  for (const auto& [view, t] : ComparedViews(calibration, truth))
    samples.push_back(
        MakeUncertaintySample(view->cam_from_box, t->cam_from_box, view->uncertainty));
  return ObservedOverPredicted(samples);
}

std::optional<double> CornerNoise(const StoredCalibration& calibration, const TruthViews& truth,
                                  const CalibBox& box) {
  double sq = 0;
  int corners = 0;
  for (const auto& [view, t] : ComparedViews(calibration, truth)) {
    for (const StoredCalibration::Tag& tag : view->tags) {
      const BoxTag* model = box.FindTag(tag.id);
      if (model == nullptr) continue;
      for (size_t k = 0; k < 4; ++k, ++corners) {
        const Eigen::Vector2d truth_px =
            Project(t->intrinsics, t->cam_from_box * model->corners_box_mm[k]);
        sq += (tag.corners_px[k] - truth_px).squaredNorm();
      }
    }
  }
  if (corners == 0) return std::nullopt;
  return std::sqrt(sq / corners);
}

// "    rotation   median ...  max ... deg"; nothing for no values.
std::string ErrorRow(const char* name, const ErrorSpread& spread, const char* unit) {
  if (spread.values.empty()) return "";
  return StringPrintf("    %-22s median %9.4f  max %9.4f %s\n", name, Median(spread.values),
                      *std::max_element(spread.values.begin(), spread.values.end()), unit);
}

std::string PoseErrorRows(const PoseErrors& e) {
  return ErrorRow("rotation", e.rotation_deg, "deg") +
         ErrorRow("camera centre", e.camera_centre_mm, "mm") +
         ErrorRow("focal length", e.focal_percent, "%") +
         ErrorRow("principal point", e.principal_point_px, "px");
}

}  // namespace

nlohmann::json ErrorSpread::ToJson() const {
  if (values.empty()) return {{"median", nullptr}, {"max", nullptr}};
  return {{"median", Median(values)}, {"max", *std::max_element(values.begin(), values.end())}};
}

nlohmann::json PoseErrors::ToJson() const {
  return {{"rotation_deg", rotation_deg.ToJson()},
          {"camera_centre_mm", camera_centre_mm.ToJson()},
          {"focal_percent", focal_percent.ToJson()},
          {"principal_point_px", principal_point_px.ToJson()}};
}

nlohmann::json CalibrationEvaluation::ToJson() const {
  nlohmann::json out{{"stage", "calibration"}, {"dir", dir}, {"mode", mode}};
  out["solved"] = solved.ToJson();
  out["solved"]["reprojection_rms_px"] = reprojection_rms_px.ToJson();
  out["initial"] = initial.ToJson();
  out["initial_source"] = initial_source;
  out["corner_noise_px"] =
      corner_noise_px ? nlohmann::json(*corner_noise_px) : nlohmann::json(nullptr);
  out["overall_rms_px"] = overall_rms_px;
  if (corner_noise_px) out["rms_over_corner_noise"] = overall_rms_px / *corner_noise_px;
  const UncertaintyRatios& u = uncertainty;
  out["uncertainty"] = u.views == 0
                           ? nlohmann::json{{"views", 0}}
                           : nlohmann::json{{"views", u.views},
                                            {"rotation_ratio", u.rotation},
                                            {"centre_ratio", u.centre},
                                            {"rotation_mahalanobis_ratio", u.rotation_mahalanobis},
                                            {"centre_mahalanobis_ratio", u.centre_mahalanobis}};
  out["views_compared"] = views_compared;
  out["views"] = views;
  out["box_alignment"] = {{"rotation_deg", box_alignment_deg},
                          {"translation_mm", box_alignment_mm}};
  return out;
}

std::string CalibrationEvaluation::BriefReport() const {
  std::string text =
      StringPrintf("calibration of %s (%s mode) against the ground truth, %d of %d views\n",
                   dir.c_str(), mode.c_str(), views_compared, views);
  text += "  bundle adjustment:\n" + PoseErrorRows(solved) +
          ErrorRow("reprojection RMS", reprojection_rms_px, "px");
  text += "  initial (" + initial_source + "):\n" + PoseErrorRows(initial);
  if (box_alignment_mm > 1e-6 || box_alignment_deg > 1e-6) {
    text += StringPrintf(
        "  poses compared in the true tags' frame (the calibration's box frame is %.4f mm, %.4f "
        "deg from it)\n",
        box_alignment_mm, box_alignment_deg);
  }
  if (corner_noise_px) {
    text += StringPrintf(
        "  reprojection RMS %.4f px against corner noise %.4f px (detections vs truth): %.2fx\n",
        overall_rms_px, *corner_noise_px, overall_rms_px / *corner_noise_px);
  }
  const UncertaintyRatios& u = uncertainty;
  if (u.views > 0) {
    text += StringPrintf(
        "  observed / predicted error (1 = the stated uncertainty is right), %d views: rotation "
        "%.2f, centre %.2f (Mahalanobis %.2f, %.2f)\n",
        u.views, u.rotation, u.centre, u.rotation_mahalanobis, u.centre_mahalanobis);
  }
  return text;
}

Result<CalibrationEvaluation> EvaluateCalibration(const StoredCalibration& calibration,
                                                  const CaptureTruth& truth,
                                                  const EvaluationBoxes& boxes) {
  const std::vector<int> used = TagIdsUsed(calibration);
  if (!SharesATag(boxes.estimated, boxes.truth, used))
    return FailedPrecondition(
        "the calibration's box and the box the images show have no tag in common: was the "
        "capture calibrated against another box?");
  const Rigid3d truth_from_estimated = TruthFromEstimatedBox(boxes.estimated, boxes.truth, used);
  const StoredCalibration aligned = InTrueBoxFrame(calibration, truth_from_estimated);
  CalibrationEvaluation e;
  e.mode = calibration.mode;
  e.views = static_cast<int>(calibration.views.size());
  e.views_compared = static_cast<int>(ComparedViews(aligned, truth.views).size());
  if (e.views_compared == 0)
    return FailedPrecondition("no solved view has a ground truth to compare with");
  e.solved = ComparePoses(aligned, truth.views, false);
  e.initial = ComparePoses(aligned, truth.views, true);
  const bool from_views = std::any_of(calibration.cameras.begin(), calibration.cameras.end(),
                                      [](const auto& c) { return c.intrinsics_source == "views"; });
  e.initial_source = from_views ? "Zhang per camera + per-view IPPE" : "nominal intrinsics";
  for (const StoredCalibration::View& view : calibration.views)
    if (view.solved) e.reprojection_rms_px.values.push_back(view.rms_px);
  e.overall_rms_px = calibration.rms_px;
  e.corner_noise_px = CornerNoise(calibration, truth.views, boxes.truth);
  e.uncertainty = CompareUncertainty(aligned, truth.views);
  e.box_alignment_deg = RotationDifferenceDeg(truth_from_estimated, Rigid3d());
  e.box_alignment_mm = truth_from_estimated.translation.norm();
  return e;
}

Rigid3d TruthFromEstimatedBox(const CalibBox& estimated, const CalibBox& truth,
                              const std::vector<int>& tag_ids) {
  std::vector<Eigen::Vector3d> from, to;
  for (const BoxTag& tag : estimated.tags) {
    const BoxTag* true_tag = truth.FindTag(tag.id);
    const bool chosen =
        tag_ids.empty() || std::find(tag_ids.begin(), tag_ids.end(), tag.id) != tag_ids.end();
    if (true_tag == nullptr || !chosen) continue;
    from.insert(from.end(), tag.corners_box_mm.begin(), tag.corners_box_mm.end());
    to.insert(to.end(), true_tag->corners_box_mm.begin(), true_tag->corners_box_mm.end());
  }
  if (from.size() < 3) return Rigid3d();
  Eigen::Matrix3Xd src(3, from.size()), dst(3, to.size());
  for (size_t i = 0; i < from.size(); ++i) {
    src.col(static_cast<Eigen::Index>(i)) = from[i];
    dst.col(static_cast<Eigen::Index>(i)) = to[i];
  }
  const Eigen::Matrix4d fit = Eigen::umeyama(src, dst, /*with_scaling=*/false);
  return Rigid3d(Eigen::Quaterniond(Eigen::Matrix3d(fit.topLeftCorner<3, 3>())),
                 fit.topRightCorner<3, 1>());
}

Result<CameraIntrinsics> ReadChArUcoTruthIntrinsics(const std::string& path) {
  HR_ASSIGN_OR_RETURN(
      const nlohmann::json truth,
      ReadJsonFile(path, "only image sets from `hairrig sim charuco` have a ground truth"));
  const JsonObject fields(truth, path);
  if (fields.StringOr("format", "") != "hairrig-charuco-truth" || !fields.ok())
    return CorruptData(path + ": not a ChArUco ground truth (format hairrig-charuco-truth)");
  const CameraIntrinsics intrinsics = IntrinsicsField(fields, "intrinsics");
  HR_RETURN_IF_ERROR(fields.status());
  return intrinsics;
}

Status IntrinsicsEvalOptions::Check() const {
  if (dir.empty())
    return InvalidArgument("eval intrinsics: dir (the calibrated image folder) is required");
  return Status::Ok();
}

nlohmann::json IntrinsicsEvaluation::ToJson() const {
  const auto t = truth.ToParams(), e = solved.ToParams();
  nlohmann::json params;
  for (size_t p = 0; p < t.size(); ++p) {
    params[CameraIntrinsics::kParamNames[p]] = {
        {"truth", t[p]},
        {"solved", e[p]},
        {"error", e[p] - t[p]},
        {"stddev", stddev[p]},
        {"error_in_stddev", stddev[p] > 0 ? (e[p] - t[p]) / stddev[p] : 0}};
  }
  return {{"stage", "intrinsics"},
          {"dir", dir},
          {"serial", serial},
          {"focal_percent", focal_percent},
          {"principal_point_px", principal_point_px},
          {"worst_error_in_stddev", worst_error_in_stddev},
          {"params", params}};
}

std::string IntrinsicsEvaluation::BriefReport() const {
  std::string text = StringPrintf(
      "intrinsics of %s in %s against the ground truth: focal %.4f %%, principal point %.3f px, "
      "worst parameter %.2f sd off\n",
      serial.c_str(), dir.c_str(), focal_percent, principal_point_px, worst_error_in_stddev);
  // The parameters by name, as the JSON lists them.
  std::array<size_t, CameraIntrinsics::kNumParams> order;
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [](size_t a, size_t b) {
    return std::string(CameraIntrinsics::kParamNames[a]) < CameraIntrinsics::kParamNames[b];
  });
  const auto t = truth.ToParams(), e = solved.ToParams();
  for (const size_t p : order) {
    const double sigmas = stddev[p] > 0 ? (e[p] - t[p]) / stddev[p] : 0;
    text += StringPrintf("  %-6s truth %12.6f solved %12.6f error %+10.3g (%+.2f sd)\n",
                         CameraIntrinsics::kParamNames[p], t[p], e[p], e[p] - t[p], sigmas);
  }
  return text;
}

Result<IntrinsicsEvaluation> EvaluateIntrinsicsFolder(const IntrinsicsEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  namespace fs = std::filesystem;
  IntrinsicsEvaluation e;
  e.dir = options.dir;
  HR_ASSIGN_OR_RETURN(
      e.truth, ReadChArUcoTruthIntrinsics((fs::path(options.dir) / "ground_truth.json").string()));
  const std::string solved_path = (fs::path(options.dir) / "intrinsics.json").string();
  HR_ASSIGN_OR_RETURN(const std::vector<IntrinsicsPrior> solved, ReadIntrinsicsPriors(solved_path));
  if (solved.size() != 1)
    return CorruptData(solved_path + ": not the result of `hairrig calibrate-intrinsics`");
  e.serial = solved[0].serial;
  e.solved = solved[0].intrinsics;
  e.stddev = solved[0].stddev;
  e.focal_percent = FocalPercent(e.solved, e.truth);
  e.principal_point_px = PrincipalPointPx(e.solved, e.truth);
  const auto t = e.truth.ToParams(), s = e.solved.ToParams();
  for (size_t p = 0; p < t.size(); ++p)
    if (e.stddev[p] > 0)
      e.worst_error_in_stddev =
          std::max(e.worst_error_in_stddev, std::abs((s[p] - t[p]) / e.stddev[p]));
  return e;
}

}  // namespace hairrig
