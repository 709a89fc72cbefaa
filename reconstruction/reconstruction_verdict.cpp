#include "reconstruction/reconstruction_verdict.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/statistics.h"
#include "core/string_format.h"
#include "reconstruction/skin_views.h"

namespace hairrig {

namespace {

double Percent(double share) { return 100.0 * share; }

double PolylineLengthMm(const StrandSet& strands, size_t first, uint32_t count) {
  double length = 0;
  for (uint32_t i = 1; i < count; ++i)
    length += (strands.points_mm[first + i] - strands.points_mm[first + i - 1]).norm();
  return length;
}

double MedianStrandLengthMm(const StrandSet& strands) {
  std::vector<double> lengths;
  lengths.reserve(strands.point_counts.size());
  size_t first = 0;
  for (const uint32_t count : strands.point_counts) {
    lengths.push_back(PolylineLengthMm(strands, first, count));
    first += count;
  }
  return Median(std::move(lengths));
}

// The largest 2nd-98th percentile range of the points along x, y or z.
double HairExtentMm(const std::vector<OrientedPoint>& points) {
  double extent = 0;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<float> values;
    values.reserve(points.size());
    for (const OrientedPoint& p : points) values.push_back(p.position_mm[axis]);
    extent = std::max(extent, Quantile(values, 0.98) - Quantile(values, 0.02));
  }
  return extent;
}

void Raise(ReconstructionVerdict::Level level, ReconstructionVerdict* verdict) {
  verdict->level = std::max(verdict->level, level);
}

// Raises the verdict for `value` below `check` (check) or `failed` (failed)
// and returns the level's word and its threshold for the reason; nullptr
// when `value` is at or above `check`.
const char* RaiseBelow(double value, double check, double failed, double* threshold,
                       ReconstructionVerdict* verdict) {
  if (value >= check) return nullptr;
  const bool is_failed = value < failed;
  Raise(is_failed ? ReconstructionVerdict::Level::kFailed : ReconstructionVerdict::Level::kCheck,
        verdict);
  *threshold = is_failed ? failed : check;
  return is_failed ? "failed" : "check";
}

void JudgeAgreement(const FusionSummary& fusion, const ReconstructionVerdictOptions& o,
                    ReconstructionVerdict* verdict) {
  if (fusion.candidates <= 0 || fusion.points <= 0) {
    Raise(ReconstructionVerdict::Level::kFailed, verdict);
    verdict->reasons.push_back(
        fusion.candidates <= 0
            ? "the stereo found no depth under the fusion's cost limit in any view"
            : "no depth cell is confirmed by another view: no points");
    return;
  }
  const double confirmed =
      static_cast<double>(fusion.depth_confirmed) / static_cast<double>(fusion.candidates);
  if (confirmed < o.failed_confirmed_share) {
    Raise(ReconstructionVerdict::Level::kFailed, verdict);
    verdict->reasons.push_back(StringPrintf(
        "only %.1f %% of the depth cells are at a depth another view confirms (failed below "
        "%.0f %%): the views disagree on where the hair is; check the calibration's verdict and "
        "the views' overlap",
        Percent(confirmed), Percent(o.failed_confirmed_share)));
  }
  if (fusion.depth_pairs <= 0) return;
  const double directions =
      static_cast<double>(fusion.direction_pairs) / static_cast<double>(fusion.depth_pairs);
  double threshold = 0;
  const char* level = RaiseBelow(directions, o.check_direction_agreement,
                                 o.failed_direction_agreement, &threshold, verdict);
  if (level == nullptr) return;
  const bool failed = directions < o.failed_direction_agreement;
  verdict->reasons.push_back(StringPrintf(
      "where two views agree on the hair's depth, only %.1f %% agree on its direction (%s below "
      "%.0f %%): the orientation maps %s; see orientation/*.jpg",
      Percent(directions), level, Percent(threshold),
      failed ? "do not show the hair's flow"
             : "follow the hair less well than on clear images (noise, glints, defocus)"));
}

void JudgePoints(const PointReconstructionSummary& points, const ReconstructionVerdictOptions& o,
                 ReconstructionVerdict* verdict) {
  std::vector<std::string> unclear;
  for (const ViewPointsSummary& v : points.views) {
    if (v.median_orientation_confidence >= o.min_view_confidence) continue;
    verdict->views_to_check.push_back(v.name);
    unclear.push_back(StringPrintf(
        "view %s: the hair's orientation is unclear (median confidence %.3f, "
        "below %.2f); see orientation/%s.jpg",
        v.name.c_str(), v.median_orientation_confidence, o.min_view_confidence, v.name.c_str()));
  }
  if (2 * unclear.size() > points.views.size()) {
    Raise(ReconstructionVerdict::Level::kFailed, verdict);
    verdict->reasons.push_back(StringPrintf(
        "%zu of %zu views show no clear hair orientation: the images do not show the hair's "
        "flow (focus, exposure, motion blur)",
        unclear.size(), points.views.size()));
  } else if (!unclear.empty()) {
    Raise(ReconstructionVerdict::Level::kCheck, verdict);
  }
  verdict->reasons.insert(verdict->reasons.end(), unclear.begin(), unclear.end());

  JudgeAgreement(points.fusion, o, verdict);
}

void JudgeStrands(const StrandPlausibility& s, const ReconstructionVerdictOptions& o,
                  ReconstructionVerdict* verdict) {
  if (s.strands <= 0) {
    Raise(ReconstructionVerdict::Level::kFailed, verdict);
    verdict->reasons.push_back("no strands were grown");
    return;
  }
  if (s.views_measured == 0) {
    Raise(ReconstructionVerdict::Level::kCheck, verdict);
    verdict->reasons.push_back(
        "strands over skin not checked: no view's label mask (masks/<view>_label.png) could be "
        "read; run the points stage again");
  }
  if (s.hair_extent_mm > 0) {
    const double share = s.median_length_mm / s.hair_extent_mm;
    double threshold = 0;
    if (const char* level =
            RaiseBelow(share, o.check_length_share, o.failed_length_share, &threshold, verdict)) {
      verdict->reasons.push_back(StringPrintf(
          "the strands are short: median %.0f mm where the hair spans %.0f mm (%s below "
          "%.0f %% of it); growth stops where the 3D orientation is missing",
          s.median_length_mm, s.hair_extent_mm, level, Percent(threshold)));
    }
  }
  if (s.samples_facing > 0 && s.over_skin_share() > o.max_over_skin_share) {
    Raise(ReconstructionVerdict::Level::kCheck, verdict);
    verdict->reasons.push_back(
        StringPrintf("%.1f %% of the strand samples facing a camera lie over skin (above %.0f %%): "
                     "strands run over the face or neck; see strands/over_views.jpg",
                     Percent(s.over_skin_share()), Percent(o.max_over_skin_share)));
  }
}

}  // namespace

Status ReconstructionVerdictOptions::Check() const {
  const std::array<std::pair<const char*, double>, 7> shares = {{
      {"min_view_confidence", min_view_confidence},
      {"failed_confirmed_share", failed_confirmed_share},
      {"check_direction_agreement", check_direction_agreement},
      {"failed_direction_agreement", failed_direction_agreement},
      {"check_length_share", check_length_share},
      {"failed_length_share", failed_length_share},
      {"max_over_skin_share", max_over_skin_share},
  }};
  for (const auto& [name, value] : shares)
    if (!(value >= 0 && value <= 1))
      return InvalidArgument(StringPrintf("verdict %s %g is not in [0, 1]", name, value));
  if (failed_direction_agreement > check_direction_agreement)
    return InvalidArgument("verdict failed_direction_agreement is above check_direction_agreement");
  if (failed_length_share > check_length_share)
    return InvalidArgument("verdict failed_length_share is above check_length_share");
  return Status::Ok();
}

double StrandPlausibility::over_skin_share() const {
  return samples_facing > 0
             ? static_cast<double>(samples_over_skin) / static_cast<double>(samples_facing)
             : 0.0;
}

nlohmann::json StrandPlausibility::ToJson() const {
  return {{"strands", strands},
          {"median_length_mm", median_length_mm},
          {"hair_extent_mm", hair_extent_mm},
          {"views_measured", views_measured},
          {"samples_facing", samples_facing},
          {"samples_over_skin", samples_over_skin},
          {"over_skin_share", over_skin_share()}};
}

const char* ReconstructionVerdict::name() const {
  return level == Level::kGood ? "good" : level == Level::kCheck ? "check" : "failed";
}

nlohmann::json ReconstructionVerdict::ToJson() const {
  return {{"verdict", name()}, {"reasons", reasons}, {"views_to_check", views_to_check}};
}

Result<StrandPlausibility> MeasureStrandPlausibility(const StrandSet& strands,
                                                     const std::vector<OrientedPoint>& points,
                                                     const SkinViews* skin, int sample_step) {
  if (sample_step < 1) return InvalidArgument("strand plausibility: sample_step must be >= 1");
  StrandPlausibility s;
  s.strands = static_cast<int64_t>(strands.point_counts.size());
  s.median_length_mm = MedianStrandLengthMm(strands);
  s.hair_extent_mm = points.empty() ? 0.0 : HairExtentMm(points);
  if (skin == nullptr) return s;
  s.views_measured = skin->views_loaded();
  for (size_t i = 0; i < strands.points_mm.size(); i += static_cast<size_t>(sample_step)) {
    int facing = 0, over_skin = 0;
    skin->Count(strands.points_mm[i].cast<double>(), &facing, &over_skin);
    s.samples_facing += facing;
    s.samples_over_skin += over_skin;
  }
  return s;
}

ReconstructionVerdict JudgeReconstruction(const PointReconstructionSummary* points,
                                          const StrandPlausibility* strands,
                                          const ReconstructionVerdictOptions& options) {
  ReconstructionVerdict verdict;
  if (points) JudgePoints(*points, options, &verdict);
  if (strands) JudgeStrands(*strands, options, &verdict);
  return verdict;
}

}  // namespace hairrig
