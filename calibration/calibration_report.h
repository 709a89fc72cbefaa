// The calibration report a technician reads at a glance
// (<capture>/calibration/report/):
//
//   report.txt           the verdict (good / check these views / failed, with
//                        why), per-camera intrinsics and their standard
//                        deviations, per-view RMS, failed views and rejected tags
//   verdict.json         the verdict for programs: {"verdict", "reasons",
//                        "views_to_check": [frame names]}
//   view_rms.png         per-view reprojection RMS as a bar chart (red: outlier
//                        or failed)
//   residuals/<frame>.jpg  each solved view at half size with the corners'
//                        residual vectors drawn x kResidualScale
#pragma once

#include <string>
#include <vector>

#include "calibration/capture_calibration.h"

namespace hairrig {

inline constexpr double kResidualScale = 100;

struct CalibrationVerdict {
  enum class Level { kGood, kCheck, kFailed } level = Level::kGood;
  std::vector<std::string> reasons;  // one line each; empty when good
  std::vector<int> views_to_check;   // input frame indices: failed or outliers
  const char* name() const {
    return level == Level::kGood ? "good" : level == Level::kCheck ? "check these views" : "failed";
  }
};

// Outlier: a view whose RMS exceeds max(3 x the median view RMS, 0.5 px).
// Failed: less than half the views solved, an overall RMS above 2 px, or a
// camera's intrinsics prior rejected by its views (PriorCheck::rejected; the
// reason names the camera, the prior's file and the parameter that disagrees).
CalibrationVerdict JudgeCalibration(const CaptureCalibrationInput& input,
                                    const CaptureCalibration& result);

// Writes the files above under `dir` (created), the residual images on
// `threads` threads. A solved view whose frame cannot be read
// (core/image_file.h ReadImageFile: missing, not an image, claiming more than
// kMaxImagePixels) or drawn gets no residual image: its line in report.txt
// says why. IoError names a file that cannot be written.
Status WriteCalibrationReport(const std::string& dir, const CaptureCalibrationInput& input,
                              const CaptureCalibration& result, const CalibrationVerdict& verdict,
                              int threads);

}  // namespace hairrig
