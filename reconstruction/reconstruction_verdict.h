// The reconstruction's verdict, as the calibration has one
// (calibration/calibration_report.h): good, check or failed, with one line
// per reason, so that a result that collapsed is never reported as a plain
// success. Every test is on figures the pipeline measures itself, none on
// ground truth, so it holds on photographs as on the simulated rig:
//
//   orientation   per view, the median orientation confidence over the hair
//                 (OrientationMap::confidence, 0..1): low where the images do
//                 not show the hair's flow (defocus, motion blur, a wrong
//                 exposure), named per view;
//   agreement     where two views agree on a depth cell's depth, the share
//                 that agree on its direction too (point_fusion.h
//                 FusionSummary): orientation maps that do not follow the
//                 hair (images unlike the ones the filters were made for)
//                 put the points in the right place with directions that no
//                 other view confirms; and the share of cells confirmed at
//                 all: cameras that do not agree leave most unconfirmed;
//   lengths       the strands' median length against the extent of the hair
//                 points (their largest 2nd-98th percentile range along an
//                 axis of the object frame): growth that stopped at once;
//   skin          strand samples that lie nearer a camera than the head's
//                 centre and project onto pixels segmented as the head
//                 (masks/<view>_label.png): strands running over the face or
//                 neck.
//
// The thresholds are ReconstructionVerdictOptions'; docs/accuracy.md gives
// the figures they were set from.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/point_reconstruction.h"

namespace hairrig {

class SkinViews;  // skin_views.h

struct ReconstructionVerdictOptions {
  // A view whose median orientation confidence over the hair is below this
  // is named; when more than half of the views are, the verdict is failed.
  double min_view_confidence = 0.1;
  // Of the view pairs that agree on a depth cell's depth, the share that
  // agree on its direction (FusionSummary): check below the first, failed
  // below the second.
  double check_direction_agreement = 0.45;
  double failed_direction_agreement = 0.25;
  // Failed below this share of depth cells confirmed by another view.
  double failed_confirmed_share = 0.05;
  // The strands' median length over the hair's extent: check below the
  // first, failed below the second.
  double check_length_share = 0.15;
  double failed_length_share = 0.05;
  // Check above this share of the strand samples facing a camera over skin.
  double max_over_skin_share = 0.02;

  // InvalidArgument naming the field for a share outside [0, 1] or a failed
  // threshold above its check threshold.
  Status Check() const;
};

// What the strands stage's output shows of itself (MeasureStrandPlausibility).
struct StrandPlausibility {
  int64_t strands = 0;
  double median_length_mm = 0;
  double hair_extent_mm = 0;  // 0 when there are no points
  int views_measured = 0;     // views whose label mask could be read
  // (strand sample, view) pairs with the sample nearer the camera than the
  // head's centre and inside the image; of those, the ones over skin.
  int64_t samples_facing = 0, samples_over_skin = 0;

  double over_skin_share() const;
  nlohmann::json ToJson() const;
};

struct ReconstructionVerdict {
  enum class Level { kGood, kCheck, kFailed } level = Level::kGood;
  std::vector<std::string> reasons;         // one line each; empty when good
  std::vector<std::string> views_to_check;  // names of the views whose orientation is unclear
  const char* name() const;                 // "good", "check", "failed"
  nlohmann::json ToJson() const;            // {"verdict", "reasons", "views_to_check"}
};

// Measures `strands` (the object frame, mm) against the fused `points` and
// the views' skin (skin_views.h; null: over skin not measured, views_measured
// 0). Every `sample_step`-th point of the set (the strands' points taken as
// one list) is projected into every view. InvalidArgument for
// sample_step < 1.
Result<StrandPlausibility> MeasureStrandPlausibility(const StrandSet& strands,
                                                     const std::vector<OrientedPoint>& points,
                                                     const SkinViews* skin, int sample_step = 4);

// Either argument may be null (a stage that did not run is not judged).
ReconstructionVerdict JudgeReconstruction(const PointReconstructionSummary* points,
                                          const StrandPlausibility* strands,
                                          const ReconstructionVerdictOptions& options = {});

}  // namespace hairrig
