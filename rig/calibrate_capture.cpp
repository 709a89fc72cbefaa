#include "rig/calibrate_capture.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "calibration/calibration_io.h"
#include "calibration/prior_check.h"
#include "calibration/tag_detection_sink.h"
#include "core/string_format.h"
#include "core/truth_maps.h"

namespace hairrig {

namespace fs = std::filesystem;

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

int SolvedViews(const CaptureCalibration& result) {
  int solved = 0;
  for (const FrameCalibration& f : result.frames) solved += f.solved;
  return solved;
}

}  // namespace

nlohmann::json CalibratedFolder::ToJson() const {
  return nlohmann::json{{"dir", out_dir},
                        {"mode", result.mode == CalibrationMode::kFree ? "free" : "turntable"},
                        {"verdict", verdict.name()},
                        {"reasons", verdict.reasons},
                        {"views", result.frames.size()},
                        {"views_solved", SolvedViews(result)},
                        {"rms_px", result.rms_px},
                        {"converged", result.converged},
                        {"detect_s", result.detect_s},
                        {"init_s", result.init_s},
                        {"solve_s", result.solve_s},
                        {"prior_checks", PriorChecksJson(*this)},
                        {"prior_check_s", result.prior_check_s},
                        {"write_s", write_s},
                        {"report_s", report_s},
                        {"report", out_dir + "/report/report.txt"}};
}

std::string CalibratedFolder::BriefReport() const {
  std::string text =
      StringPrintf("calibration %s (%s mode): %s\n", out_dir.c_str(),
                   result.mode == CalibrationMode::kFree ? "free" : "turntable", verdict.name());
  for (const std::string& reason : verdict.reasons) text += "  - " + reason + "\n";
  text += StringPrintf(
      "  %d of %d views solved, RMS %.3f px; detection %.2f s, initialisation %.2f s, bundle "
      "adjustment %.2f s, writing %.2f s + report %.2f s\n",
      SolvedViews(result), static_cast<int>(result.frames.size()), result.rms_px, result.detect_s,
      result.init_s, result.solve_s, write_s, report_s);
  text += "  report: " + out_dir + "/report/report.txt\n";
  return text;
}

Status CalibrateFolderOptions::Check() const {
  HR_RETURN_IF_ERROR(calibration.Check().WithContext("calibration"));
  for (size_t i = 0; i < prior_files.size(); ++i) {
    if (prior_files[i].empty())
      return InvalidArgument("prior_files[" + std::to_string(i) + "] is empty: name a file");
  }
  return Status::Ok();
}

Result<CalibratedFolder> CalibrateCaptureFolder(const std::string& capture_dir,
                                                const CalibrateFolderOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  CalibratedFolder done;
  HR_ASSIGN_OR_RETURN(done.input, LoadCaptureCalibrationInput(capture_dir));
  CaptureCalibrationOptions calibration = options.calibration;
  if (!options.prior_files.empty()) {
    HR_RETURN_IF_ERROR(ApplyIntrinsicsPriors(options.prior_files, &done.input));
    calibration.fix_intrinsics = true;
  }
  if (!options.box_file.empty()) {
    HR_ASSIGN_OR_RETURN(done.input.box, LoadCalibBox(options.box_file));
    done.input.box_source = fs::absolute(options.box_file).string();
  }
  if (options.detected != nullptr) {
    for (CalibrationFrame& frame : done.input.frames) {
      const auto found = options.detected->find(DetectionKey(frame.path));
      if (found != options.detected->end()) frame.observations = found->second;
    }
  }
  HR_ASSIGN_OR_RETURN(done.result, CalibrateCapture(done.input, calibration));
  done.out_dir = (std::filesystem::path(capture_dir) / "calibration").string();
  const auto write_start = std::chrono::steady_clock::now();
  HR_RETURN_IF_ERROR(WriteCalibration(done.out_dir, done.input, done.result));
  done.write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count();
  if (options.on_written) options.on_written();
  done.verdict = JudgeCalibration(done.input, done.result);
  HR_RETURN_IF_ERROR(WriteCalibrationReport(done.out_dir + "/report", done.input, done.result,
                                            done.verdict, calibration.threads));
  done.report_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count() -
      done.write_s;
  return done;
}

Status RefineBoxOptions::Check() const {
  if (capture_dirs.empty())
    return InvalidArgument("calibrate-box: name at least one capture folder");
  if (out_file.empty())
    return InvalidArgument("calibrate-box: --out (the box file to write) is required");
  for (size_t i = 0; i < prior_files.size(); ++i) {
    if (prior_files[i].empty())
      return InvalidArgument("prior_files[" + std::to_string(i) + "] is empty: name a file");
  }
  if (calibration.box_tolerance.Zero())
    return InvalidArgument(
        "calibration: box_tolerance is zero: nothing of the box would be refined");
  return calibration.Check().WithContext("calibration");
}

namespace {

// One capture of RefineBoxFromCaptures, solved against `box`.
Result<RefinedBox::Step> RefineBoxStep(const std::string& capture_dir,
                                       const RefineBoxOptions& options, CalibBox* box,
                                       std::string* box_source) {
  HR_ASSIGN_OR_RETURN(CaptureCalibrationInput input, LoadCaptureCalibrationInput(capture_dir));
  CaptureCalibrationOptions calibration = options.calibration;
  if (!options.prior_files.empty()) {
    HR_RETURN_IF_ERROR(ApplyIntrinsicsPriors(options.prior_files, &input));
    calibration.fix_intrinsics = true;
  }
  if (box_source->empty()) {
    *box = input.box;
    *box_source = input.box_source;
  }
  input.box = *box;
  input.box_source = *box_source;
  auto result = CalibrateCapture(input, calibration);
  if (!result.ok()) return result.status().WithContext(capture_dir);
  RefinedBox::Step step;
  step.capture_dir = capture_dir;
  step.views = static_cast<int>(result->frames.size());
  for (const FrameCalibration& frame : result->frames) step.views_solved += frame.solved;
  step.sigma_as_given_px = result->sigma_box_as_given_px;
  step.sigma_refined_px = result->sigma_box_refined_px;
  for (const TagRefinement& move : result->tag_moves) {
    step.largest_tag_move_mm = std::max(step.largest_tag_move_mm, move.moved_mm.norm());
    step.largest_tag_sd_mm = std::max(step.largest_tag_sd_mm, move.moved_sd_mm.maxCoeff());
  }
  step.verdict = JudgeCalibration(input, *result).name();
  *box = result->box_as_built;
  *box_source = capture_dir + "/(refined)";
  return step;
}

}  // namespace

Result<RefinedBox> RefineBoxFromCaptures(const RefineBoxOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  RefinedBox out;
  out.out_file = options.out_file;
  std::string source;
  if (!options.box_file.empty()) {
    HR_ASSIGN_OR_RETURN(out.box, LoadCalibBox(options.box_file));
    source = options.box_file;
  }
  for (const std::string& dir : options.capture_dirs) {
    HR_ASSIGN_OR_RETURN(RefinedBox::Step step, RefineBoxStep(dir, options, &out.box, &source));
    out.steps.push_back(std::move(step));
  }
  std::string captures;
  for (const std::string& dir : options.capture_dirs) captures += "\n  " + dir;
  HR_RETURN_IF_ERROR(
      WriteCalibBox(out.box, options.out_file,
                    "The calibration box as built, refined by `hairrig calibrate-box` "
                    "from the captures below in turn,\nstarting from the box in the "
                    "first one's rig config or --box:" +
                        captures));
  return out;
}

nlohmann::json RefinedBox::ToJson() const {
  nlohmann::json steps_json = nlohmann::json::array();
  for (const Step& step : steps) {
    steps_json.push_back({{"capture", step.capture_dir},
                          {"views", step.views},
                          {"views_solved", step.views_solved},
                          {"sigma_as_given_px", step.sigma_as_given_px},
                          {"sigma_refined_px", step.sigma_refined_px},
                          {"largest_tag_move_mm", step.largest_tag_move_mm},
                          {"largest_tag_sd_mm", step.largest_tag_sd_mm},
                          {"verdict", step.verdict}});
  }
  return {{"out", out_file}, {"captures", steps_json}};
}

std::string RefinedBox::BriefReport() const {
  std::string text = "box as built: " + out_file + "\n";
  for (const Step& step : steps) {
    text += StringPrintf(
        "  %s: %d of %d views solved, corner residuals %.3f px with the box as given, %.3f px "
        "refined; tags moved up to %.3f mm (sd up to %.3f mm); verdict %s\n",
        step.capture_dir.c_str(), step.views_solved, step.views, step.sigma_as_given_px,
        step.sigma_refined_px, step.largest_tag_move_mm, step.largest_tag_sd_mm,
        step.verdict.c_str());
  }
  return text;
}

Status CaptureCalibrationEvalOptions::Check() const {
  if (capture_dir.empty())
    return InvalidArgument("eval calibration: capture_dir (the capture folder) is required");
  return Status::Ok();
}

namespace {

// The box a capture's calibration solved against: its refined box when it
// refined one, else the box file it was given (the rig config's when that is
// the one named). FailedPrecondition names the file calibration.json needs
// and cannot find.
Result<CalibBox> CalibratedBoxOf(const std::string& dir, const StoredCalibration& calibration,
                                 const CalibrationSection& section) {
  const fs::path calibration_json = fs::path(dir) / "calibration" / "calibration.json";
  if (calibration.box_refined) {
    const fs::path refined = fs::path(dir) / "calibration" / "box_as_built.yaml";
    if (!fs::exists(refined))
      return FailedPrecondition(refined.string() +
                                ": missing, though calibration.json says the calibration refined "
                                "the box; calibrate the capture again");
    return LoadCalibBox(refined.string());
  }
  if (calibration.box_file.empty() || calibration.box_file == section.box_file) return section.box;
  if (!fs::exists(calibration.box_file))
    return FailedPrecondition(calibration_json.string() +
                              ": field 'box.file': " + calibration.box_file +
                              " (the box the calibration was given) is not there; calibrate "
                              "again with the box at hand");
  return LoadCalibBox(calibration.box_file);
}

// The boxes an evaluation compares: the calibration's (CalibratedBoxOf) and
// the one the simulated rig drew, ground_truth/box_as_built.yaml (verified
// against the ground truth's checksums), else the rig config's box (captures
// whose ground truth predates the box as built show the drawn box).
Result<EvaluationBoxes> EvaluationBoxesOf(const std::string& dir, const CaptureTruth& truth,
                                          const StoredCalibration& calibration) {
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(dir));
  HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
  EvaluationBoxes boxes;
  HR_ASSIGN_OR_RETURN(boxes.estimated, CalibratedBoxOf(dir, calibration, section));
  const fs::path true_box = fs::path(truth.dir) / "box_as_built.yaml";
  if (!fs::exists(true_box)) {
    boxes.truth = section.box;
    return boxes;
  }
  HR_RETURN_IF_ERROR(VerifyTruthFile(truth, true_box.string()));
  HR_ASSIGN_OR_RETURN(boxes.truth, LoadCalibBox(true_box.string()));
  return boxes;
}

}  // namespace

Result<CalibrationEvaluation> EvaluateCaptureCalibration(
    const CaptureCalibrationEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string& dir = options.capture_dir;
  HR_ASSIGN_OR_RETURN(
      const StoredCalibration calibration,
      ReadCalibration((fs::path(dir) / "calibration" / "calibration.json").string()));
  HR_ASSIGN_OR_RETURN(const CaptureTruth truth, ReadCaptureTruth(dir));
  HR_ASSIGN_OR_RETURN(const EvaluationBoxes boxes, EvaluationBoxesOf(dir, truth, calibration));
  Result<CalibrationEvaluation> evaluation = EvaluateCalibration(calibration, truth, boxes);
  if (!evaluation.ok()) return evaluation.status().WithContext(dir);
  evaluation->dir = dir;
  return evaluation;
}

}  // namespace hairrig
