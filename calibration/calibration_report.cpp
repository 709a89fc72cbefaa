#include "calibration/calibration_report.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/file_util.h"
#include "core/image_file.h"
#include "core/parallel.h"
#include "core/statistics.h"

namespace hairrig {

namespace fs = std::filesystem;

namespace {

constexpr double kOutlierFactor = 3.0;
constexpr double kOutlierFloorPx = 0.5;
constexpr double kFailedRmsPx = 2.0;
// The box is not as given when the residuals with it as given are this many
// times those with it refined (refining a box that is exact changes them by
// about 2 %: its parameters are few against the corners).
constexpr double kBoxMisfitRatio = 1.5;
// A refined tag that moved more than this many build tolerances is named.
constexpr double kTagMovedTolerances = 4.0;

double MedianSolvedRms(const CaptureCalibration& result) {
  std::vector<double> rms;
  for (const FrameCalibration& f : result.frames)
    if (f.solved) rms.push_back(f.rms_px);
  return Median(std::move(rms));
}

double OutlierThreshold(const CaptureCalibration& result) {
  return std::max(kOutlierFactor * MedianSolvedRms(result), kOutlierFloorPx);
}

std::string Format(const char* format, double a, double b = 0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, a, b);
  return buffer;
}

// A prior the views reject fails the calibration: every view of that camera
// was solved with intrinsics that are not its own.
void JudgePriors(const CaptureCalibrationInput& input, const CaptureCalibration& result,
                 CalibrationVerdict* verdict) {
  for (size_t c = result.cameras.size(); c-- > 0;) {
    const PriorCheck& check = result.cameras[c].prior_check;
    if (!check.rejected) continue;
    const CalibrationCamera& camera = input.cameras[c];
    const std::string file =
        camera.prior_source.empty() ? "its intrinsics prior" : camera.prior_source;
    verdict->level = CalibrationVerdict::Level::kFailed;
    verdict->reasons.insert(verdict->reasons.begin(),
                            "camera " + camera.name + " (" + camera.serial +
                                "): its views reject the intrinsics of " + file + ": " +
                                DescribePriorCheck(check) + "; check that " + file +
                                " belongs to camera " + camera.serial +
                                ", or recalibrate its intrinsics (`hairrig calibrate-intrinsics`)");
  }
}

// The tags that moved most in the box refinement, largest first: "3 (1.2 mm),
// 7 (0.9 mm)". At most `count` of them.
std::string LargestTagMoves(const CaptureCalibration& result, size_t count) {
  std::vector<TagRefinement> moves = result.tag_moves;
  std::sort(moves.begin(), moves.end(), [](const TagRefinement& a, const TagRefinement& b) {
    return a.moved_mm.norm() > b.moved_mm.norm();
  });
  std::string text;
  for (size_t i = 0; i < moves.size() && i < count; ++i)
    text += (i ? ", " : "") + std::to_string(moves[i].id) +
            Format(" (%.2f mm)", moves[i].moved_mm.norm());
  return text;
}

// Whether the box is the one the calibration was given: taken as exact, its
// residuals must not be well above those with the box refined; refined, no
// tag may have moved far beyond the build tolerance.
void JudgeBox(const CaptureCalibrationInput& input, const CaptureCalibration& result,
              CalibrationVerdict* verdict) {
  const std::string file = input.box_source.empty() ? "the box file" : input.box_source;
  const bool misfit = result.sigma_box_as_given_px > kBoxMisfitRatio * result.sigma_box_refined_px;
  if (!result.box_refined && misfit) {
    verdict->reasons.push_back(
        "the box is not as " + file + " says: corner residuals " +
        Format("%.2f px with it as given, %.2f px with it refined", result.sigma_box_as_given_px,
               result.sigma_box_refined_px) +
        " (the tags that moved most: " + LargestTagMoves(result, 3) +
        "); calibrate with the box refined, or give the box as built (--box)");
  }
  if (result.box_refined) {
    const BoxTolerance& tolerance = result.box_tolerance;
    for (const TagRefinement& move : result.tag_moves) {
      const bool moved = move.moved_mm.norm() > kTagMovedTolerances * tolerance.tag_center_mm;
      const bool turned = std::abs(move.turned_deg) > kTagMovedTolerances * tolerance.tag_turn_deg;
      if (!moved && !turned) continue;
      verdict->reasons.push_back(
          "tag " + std::to_string(move.id) +
          Format(" moved %.2f mm and turned %.2f deg", move.moved_mm.norm(), move.turned_deg) +
          " from its place in " + file +
          Format(" (build tolerance %.2f mm, %.2f deg)", tolerance.tag_center_mm,
                 tolerance.tag_turn_deg) +
          ": it may be peeling off, or printed with another id; fix it and refine the box again");
    }
  }
  if (!verdict->reasons.empty() && verdict->level == CalibrationVerdict::Level::kGood)
    verdict->level = CalibrationVerdict::Level::kCheck;
}

}  // namespace

CalibrationVerdict JudgeCalibration(const CaptureCalibrationInput& input,
                                    const CaptureCalibration& result) {
  CalibrationVerdict verdict;
  const double threshold = OutlierThreshold(result);
  size_t solved = 0;
  for (size_t f = 0; f < result.frames.size(); ++f) {
    const FrameCalibration& frame = result.frames[f];
    solved += frame.solved;
    if (!frame.solved) {
      verdict.views_to_check.push_back(static_cast<int>(f));
      verdict.reasons.push_back("view " + input.frames[f].name + " not solved: " + frame.failure);
    } else if (frame.rms_px > threshold) {
      verdict.views_to_check.push_back(static_cast<int>(f));
      verdict.reasons.push_back(
          "view " + input.frames[f].name +
          Format(" has RMS %.2f px (outlier threshold %.2f px)", frame.rms_px, threshold));
    }
  }
  for (size_t c = 0; c < result.cameras.size(); ++c)
    if (!result.cameras[c].solved)
      verdict.reasons.push_back("camera " + input.cameras[c].name +
                                " not solved: " + result.cameras[c].failure);
  if (!verdict.reasons.empty()) verdict.level = CalibrationVerdict::Level::kCheck;
  if (2 * solved < result.frames.size()) {
    verdict.level = CalibrationVerdict::Level::kFailed;
    verdict.reasons.insert(
        verdict.reasons.begin(),
        std::to_string(solved) + " of " + std::to_string(result.frames.size()) + " views solved");
  }
  if (result.rms_px > kFailedRmsPx) {
    verdict.level = CalibrationVerdict::Level::kFailed;
    verdict.reasons.insert(verdict.reasons.begin(), Format("overall RMS %.2f px is above %.1f px",
                                                           result.rms_px, kFailedRmsPx));
  }
  JudgeBox(input, result, &verdict);
  JudgePriors(input, result, &verdict);
  return verdict;
}

namespace {

cv::Mat RmsBarChart(const CaptureCalibrationInput& input, const CaptureCalibration& result) {
  const int bar = 16, left = 60, bottom = 40, top = 30, height = 300;
  const int width = left + bar * static_cast<int>(result.frames.size()) + 20;
  cv::Mat chart(height + top + bottom, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const double threshold = OutlierThreshold(result);
  double top_px = threshold * 1.2;
  for (const FrameCalibration& f : result.frames) top_px = std::max(top_px, f.rms_px * 1.1);
  auto y_of = [&](double px) { return top + height - static_cast<int>(height * px / top_px); };
  for (int tick = 0; tick <= 4; ++tick) {
    const double px = top_px * tick / 4;
    cv::line(chart, {left - 4, y_of(px)}, {width - 10, y_of(px)}, cv::Scalar(220, 220, 220));
    cv::putText(chart, Format("%.2f", px), {4, y_of(px) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0));
  }
  cv::line(chart, {left, y_of(threshold)}, {width - 10, y_of(threshold)}, cv::Scalar(0, 0, 200), 1,
           cv::LINE_AA);
  for (size_t f = 0; f < result.frames.size(); ++f) {
    const FrameCalibration& frame = result.frames[f];
    const int x = left + bar * static_cast<int>(f);
    const bool bad = !frame.solved || frame.rms_px > threshold;
    const cv::Scalar colour = bad ? cv::Scalar(40, 40, 220) : cv::Scalar(180, 120, 40);
    const int y = frame.solved ? y_of(frame.rms_px) : top;
    cv::rectangle(chart, {x + 2, y}, {x + bar - 2, top + height}, colour,
                  frame.solved ? cv::FILLED : 2);
    if (f % 2 == 0)
      cv::putText(chart, std::to_string(input.frames[f].view), {x, top + height + 14},
                  cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(0, 0, 0));
  }
  cv::putText(chart,
              "reprojection RMS per view (px); red line: outlier threshold; hollow: not solved",
              {left, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
  cv::putText(chart, "view", {width / 2, top + height + 32}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0));
  return chart;
}

Status DrawResiduals(const std::string& path, const cv::Mat& image, const CameraIntrinsics& camera,
                     const FrameCalibration& frame) {
  cv::Mat shown;
  cv::resize(image, shown, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  for (const TagObservation& tag : frame.tags) {
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector2d seen = tag.corners_px[k];
      const Eigen::Vector2d predicted = Project(camera, frame.cam_from_box * tag.corners_box_mm[k]);
      const Eigen::Vector2d tip = seen + kResidualScale * (predicted - seen);
      cv::circle(shown, {static_cast<int>(seen.x() / 2), static_cast<int>(seen.y() / 2)}, 2,
                 cv::Scalar(0, 255, 0), 1, cv::LINE_AA);
      cv::line(shown, {static_cast<int>(seen.x() / 2), static_cast<int>(seen.y() / 2)},
               {static_cast<int>(tip.x() / 2), static_cast<int>(tip.y() / 2)},
               cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
    }
  }
  cv::putText(shown, Format("RMS %.3f px; residuals x %.0f", frame.rms_px, kResidualScale),
              {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 2);
  return WriteImageAtomic(path, shown, {cv::IMWRITE_JPEG_QUALITY, 85});
}

// The box used, the box check and each refined tag's and face's move.
std::string BoxText(const CaptureCalibrationInput& input, const CaptureCalibration& result) {
  std::ostringstream out;
  out << "box: " << (input.box_source.empty() ? "(unnamed)" : input.box_source)
      << (result.box_refined ? ", refined with the cameras" : ", taken as exact") << "\n";
  out << Format("  corner residual sigma: %.3f px with the box as given, %.3f px refined\n",
                result.sigma_box_as_given_px, result.sigma_box_refined_px);
  if (result.tag_moves.empty()) return out.str();
  out << "  tags moved (in their face, mm; turned, deg; +- one standard deviation):\n";
  for (const TagRefinement& m : result.tag_moves) {
    out << "    tag " << m.id << " (" << m.views << " views): " << Format("%+.3f, ", m.moved_mm.x())
        << Format("%+.3f mm +- ", m.moved_mm.y())
        << Format("%.3f, %.3f", m.moved_sd_mm.x(), m.moved_sd_mm.y())
        << Format("; %+.3f deg +- %.3f\n", m.turned_deg, m.turned_sd_deg);
  }
  out << "  faces moved (along the normal, mm; tilted about u, v, deg):\n";
  for (const FaceRefinement& m : result.face_moves) {
    out << "    face " << result.box_as_built.faces[static_cast<size_t>(m.face)].name << ": "
        << Format("%+.3f mm +- %.3f; ", m.moved_mm, m.moved_sd_mm)
        << Format("%+.3f, %+.3f deg", m.tilted_u_deg, m.tilted_v_deg)
        << Format(" +- %.3f\n", m.tilted_sd_deg);
  }
  return out.str();
}

// `not_drawn`: per frame, why its residual image could not be drawn, or "".
std::string ReportText(const CaptureCalibrationInput& input, const CaptureCalibration& result,
                       const CalibrationVerdict& verdict,
                       const std::vector<std::string>& not_drawn) {
  std::ostringstream out;
  out << "verdict: " << verdict.name() << "\n";
  for (const std::string& reason : verdict.reasons) out << "  - " << reason << "\n";
  out << "\nmode " << (result.mode == CalibrationMode::kTurntable ? "turntable" : "free")
      << Format(", overall RMS %.3f px, residual sigma %.3f px", result.rms_px,
                result.residual_sigma_px)
      << ", " << result.iterations << " iterations" << (result.converged ? "" : " (NOT converged)")
      << "\n";
  out << Format("time: detection %.2f s, initialisation %.2f s", result.detect_s, result.init_s)
      << Format(", bundle adjustment %.2f s, prior check %.2f s\n\n", result.solve_s,
                result.prior_check_s);
  out << BoxText(input, result) << "\ncameras:\n";
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    const CameraCalibration& cam = result.cameras[c];
    out << "  " << input.cameras[c].name << " (" << input.cameras[c].serial << "): ";
    if (!cam.solved) {
      out << "NOT SOLVED: " << cam.failure << "\n";
      continue;
    }
    const auto params = cam.intrinsics.ToParams();
    out << "start from " << cam.intrinsics_source << "\n";
    const std::string& source = input.cameras[c].prior_source;
    if (cam.prior_check.tested || !cam.prior_check.not_tested.empty())
      out << "    prior" << (source.empty() ? "" : " " + source) << " against the views alone: "
          << (cam.prior_check.rejected ? "REJECTED, "
              : cam.prior_check.tested ? "consistent, "
                                       : "")
          << DescribePriorCheck(cam.prior_check) << "\n";
    for (size_t k = 0; k < params.size(); ++k)
      out << "    " << CameraIntrinsics::kParamNames[k]
          << Format(" = %.6g +- %.3g\n", params[k], cam.intrinsics_stddev[k]);
  }
  out << "\nviews (RMS px, tags used / detected; predicted error: rotation deg, camera centre "
         "mm):\n";
  for (size_t f = 0; f < result.frames.size(); ++f) {
    const FrameCalibration& frame = result.frames[f];
    out << "  " << input.frames[f].name << ": ";
    if (frame.solved)
      out << Format("%.3f px, ", frame.rms_px) << frame.tags.size() << " / " << frame.tags_detected
          << Format("; +- %.4f deg, %.3f mm", frame.uncertainty.rotation_sd_deg,
                    frame.uncertainty.centre_sd_mm);
    else
      out << "NOT SOLVED: " << frame.failure;
    for (const RejectedTag& r : frame.rejected)
      out << "; tag " << r.id << " left out: " << r.reason;
    if (!not_drawn[f].empty()) out << "; no residual image: " << not_drawn[f];
    out << "\n";
  }
  return out.str();
}

// The verdict for programs (the operator console, scripts): its level, the
// reasons and the frames of the views to check.
nlohmann::json VerdictJson(const CaptureCalibrationInput& input,
                           const CalibrationVerdict& verdict) {
  nlohmann::json views = nlohmann::json::array();
  for (int f : verdict.views_to_check) views.push_back(input.frames[static_cast<size_t>(f)].name);
  return {{"verdict", verdict.name()}, {"reasons", verdict.reasons}, {"views_to_check", views}};
}

}  // namespace

Status WriteCalibrationReport(const std::string& dir, const CaptureCalibrationInput& input,
                              const CaptureCalibration& result, const CalibrationVerdict& verdict,
                              int threads) {
  const fs::path root(dir);
  std::error_code ec;
  fs::create_directories(root / "residuals", ec);
  if (ec)
    return IoError((root / "residuals").string() + ": cannot create the folder (" + ec.message() +
                   ")");
  // One residual image per solved view, spread over the threads (they dominate
  // the report's time). The workers never throw: a frame that cannot be read
  // (ReadImageFile's Status) or drawn is a note on its view in report.txt.
  std::vector<Status> written(result.frames.size());
  std::vector<std::string> not_drawn(result.frames.size());
  ParallelFor(result.frames.size(), threads, [&] {
    return [&](size_t f) {
      const FrameCalibration& frame = result.frames[f];
      if (!frame.solved) return;
      const Result<cv::Mat> image = ReadImageFile(input.frames[f].path, cv::IMREAD_COLOR);
      if (!image.ok()) {
        not_drawn[f] = image.status().message();
        return;
      }
      const std::string name = fs::path(input.frames[f].name).stem().string() + ".jpg";
      try {
        written[f] = DrawResiduals(
            (root / "residuals" / name).string(), *image,
            result.cameras[static_cast<size_t>(input.frames[f].camera)].intrinsics, frame);
      } catch (const std::exception& e) {  // OpenCV's, or memory exhausted
        not_drawn[f] = input.frames[f].path + ": " + e.what();
      }
    };
  });
  HR_RETURN_IF_ERROR(WriteFileAtomic((root / "report.txt").string(),
                                     ReportText(input, result, verdict, not_drawn)));
  HR_RETURN_IF_ERROR(WriteFileAtomic((root / "verdict.json").string(),
                                     VerdictJson(input, verdict).dump(2) + "\n"));
  HR_RETURN_IF_ERROR(
      WriteImageAtomic((root / "view_rms.png").string(), RmsBarChart(input, result)));
  for (const Status& s : written) HR_RETURN_IF_ERROR(s);
  return Status::Ok();
}

}  // namespace hairrig
