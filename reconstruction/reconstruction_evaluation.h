// `hairrig eval reconstruction`: every stage of a capture's reconstruction
// (<capture>/reconstruction/, point_reconstruction.h) against the simulated
// rig's ground truth (<capture>/ground_truth/, core/truth_maps.h):
//   masks        IoU with the true hair label, per view
//   orientation  unsigned angle error on true hair pixels, and the share kept
//   depth        |depth - true depth| on the stereo grid's true hair pixels
//   points       precision, recall of the visible surface (true strand
//                samples seen by >= 2 cameras) and of all strands, F1, at the
//                protocol's thresholds (point_evaluation.h)
//   strands      when <reconstruction>/strands/strands.ply exists: the strand
//                protocol (strand_evaluation.h) with the same true samples and
//                visible surface as the points, and the true head where the
//                ground truth records one (not in captures made before it did);
//                writes strands/preview_truth.jpg, the strands above the truth
//                from four sides
// The reconstruction's object frame (points and strands) is mapped into the
// true turntable frame through the box, which both frames are fixed to:
//   truth_from_estimate = true turntable_from_box * (summary.json's object_from_box)^-1.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "reconstruction/evaluation.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/point_evaluation.h"
#include "reconstruction/strand_evaluation.h"

namespace hairrig {

struct ReconstructionEvalOptions {
  std::string reconstruction_dir;  // what to score; empty: <capture>/reconstruction
  // Where strands/strands.ply is read from (e.g. a strand bench's output
  // folder for one method); empty: the reconstruction folder.
  std::string strands_dir;
  double truth_step_mm = 1.0;  // true strands sampled every this far
  double visibility_tolerance_mm =
      2.0;                    // a camera sees a true sample within this of its true depth map
  int min_visible_views = 2;  // the visible surface: samples seen by at least this many cameras
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct ViewReconstructionAccuracy {
  std::string name;
  int view = 0;
  double mask_iou = 0;
  OrientationAccuracy orientation;
  int depth_cells = 0;  // grid cells with a depth on true hair
  double depth_mean_mm = 0;
  double depth_median_mm = 0;
};

struct ReconstructionEvaluation {
  std::vector<ViewReconstructionAccuracy> views;
  double mask_iou_median = 0, mask_iou_worst = 0;
  double orientation_median_deg = 0, orientation_p90_deg = 0,
         orientation_kept_fraction = 0;           // over all views' pixels
  double depth_median_mm = 0, depth_mean_mm = 0;  // over all views' cells
  int64_t points = 0, truth_samples = 0, visible_truth_samples = 0;
  std::vector<MatchScore> visible;  // recall against the visible surface
  std::vector<MatchScore> all;      // recall against every true strand sample
  // The strands' scores (true samples every truth_step_mm, as for the points);
  // nullopt when the reconstruction has no strands/strands.ply.
  std::optional<StrandEvaluation> strands;
  // With strands: of the (strand point, true camera) pairs where the point
  // lies in the image and is seen or in front of what is seen (not behind the
  // true depth map by more than visibility_tolerance_mm), the share whose
  // pixel shows bare skin (the true head label with under 2 % hair coverage)
  // while the point lies below the true head's hairline: strands in front of
  // the bare face, ears and neck. For the reconstruction and for the true
  // strands themselves (near 0: stray fibres). Every 2nd point.
  std::optional<double> strands_over_true_skin, truth_over_true_skin;
  // With strands: the turntable preview of the reconstruction (in the true
  // frame) above the truth's, <strands dir>/strands/preview_truth.jpg; empty
  // when it could not be written (a warning is logged, the scores stand).
  std::string strands_preview;

  // The strands under "strands" when there are any.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// NotFound when the capture has no ground truth or no reconstruction;
// CorruptData naming the file for a damaged one (a strands file included);
// the true head's error (e.g. its mesh unreadable) when it cannot be built.
Result<ReconstructionEvaluation> EvaluateReconstruction(const std::string& capture_dir,
                                                        const ReconstructionEvalOptions& options);

// Oriented points made from the ground truth, in the reconstruction's object
// frame: what a points stage with perfect input would hand the strand stage,
// to measure the strand stage's ceiling and what each of the points' faults
// costs it (bench/strand_bench.cpp --points).
enum class TruthPointsKind {
  // True samples on the visible surface (every truth_step_mm along the true
  // strands, seen by >= min_visible_views cameras), a random subset (fixed
  // seed) as large as the reconstruction's own point cloud; confidence 1.
  kVisibleSurface,
  // The reconstruction's own points, each with the direction of the nearest
  // visible true sample within 2 mm; points with none keep their own.
  kTrueDirections,
};
// Reads <reconstruction>/points.ply and summary.json and the ground truth as
// EvaluateReconstruction does, with its errors.
Result<std::vector<OrientedPoint>> PointsFromTruth(const std::string& capture_dir,
                                                   TruthPointsKind kind,
                                                   const ReconstructionEvalOptions& options);

}  // namespace hairrig
