// `hairrig reconstruct` and `capture --reconstruct` as one library call: a
// calibrated capture (or a COLMAP text model) to oriented points, then
// strands rooted on the subject's scalp, into <dir>/reconstruction/.
//
// Besides what the two stages write (reconstruction/point_reconstruction.h,
// reconstruction/strand_reconstruction.h), the strands stage writes
// reconstruction/strands/over_views.jpg: the strands projected over four of
// the input views, spread around the turntable, and
// reconstruction/strands/hair.display.glb (rig/gltf_export.h: at most 2,000
// strands and the head, for display and download); the stages that ran
// are judged (reconstruction/reconstruction_verdict.h) into
// reconstruction/verdict.json: {"verdict": good|check|failed, "reasons",
// "views_to_check"}, also first in the summary.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "reconstruction/head_fit.h"
#include "reconstruction/point_reconstruction.h"
#include "reconstruction/reconstruction_verdict.h"
#include "reconstruction/strand_reconstruction.h"

namespace hairrig {

enum class ReconstructStage { kPoints, kStrands, kAll };
// "points", "strands", "all"; InvalidArgument listing them.
Result<ReconstructStage> ParseReconstructStage(const std::string& name);

struct ReconstructCaptureOptions {
  std::string
      dir;  // a calibrated capture folder; with colmap_dir, where reconstruction/ is written
  ReconstructStage stage = ReconstructStage::kAll;
  // A COLMAP text model instead of a capture: its folder, its images and
  // (optional) hair masks named <image name>.png. Strands there need
  // head_file: a head file, or kFittedHead when the model is in mm with +z up.
  std::string colmap_dir, images_dir, masks_dir;
  std::vector<int> views;  // only these view numbers (capture) or IMAGE_IDs (COLMAP); empty: all
  // The subject's head: a head file, kFittedHead ("fit"), or empty for the
  // rig.yaml's head (fitted where it has none); ResolveSubjectHead.
  std::string head_file;
  PointReconstructionOptions points;
  StrandReconstructionOptions strands;
  ReconstructionProgress progress;  // optional

  // InvalidArgument naming the option (points.* and strands.* for the nested
  // ones, checked where the stage runs them).
  Status Check() const;
};

struct ReconstructCaptureSummary {
  std::optional<PointReconstructionSummary> points;
  std::optional<HeadFitSummary> head_fit;  // when the strands' head was fitted to the views
  std::optional<StrandReconstructionSummary> strands;
  std::string over_views_picture;  // empty when the strands stage did not run
  std::string display_glb;         // strands/hair.display.glb (rig/gltf_export.h); likewise
  std::optional<StrandPlausibility> plausibility;  // when the strands stage ran
  ReconstructionVerdict verdict;  // on the stages that ran; also written to verdict.json
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: as the stages' (no calibration, no points for --stage strands, no
// head), a --views id that is not usable, an image the overlay cannot read.
Result<ReconstructCaptureSummary> ReconstructCapture(const ReconstructCaptureOptions& options);

}  // namespace hairrig
