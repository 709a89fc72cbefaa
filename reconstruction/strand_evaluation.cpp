#include "reconstruction/strand_evaluation.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>

#include "core/statistics.h"

namespace hairrig {
namespace {

StrandLengthStats LengthStats(const StrandSet& strands) {
  StrandLengthStats s;
  const std::vector<double> lengths = strands.StrandLengths();
  s.count = static_cast<int64_t>(lengths.size());
  if (lengths.empty()) return s;
  s.mean_mm =
      std::accumulate(lengths.begin(), lengths.end(), 0.0) / static_cast<double>(lengths.size());
  s.p10_mm = Quantile(lengths, 0.1);
  s.median_mm = Median(lengths);
  s.p90_mm = Quantile(lengths, 0.9);
  return s;
}

// Per true strand with matched samples, the largest share of them whose nearest estimate sample
// comes from one estimate strand; the mean of the shares.
void MeasureConsistency(const std::vector<int64_t>& nearest,
                        const std::vector<uint32_t>& truth_sample_strand,
                        const std::vector<uint32_t>& estimate_sample_strand,
                        StrandEvaluation* out) {
  std::vector<std::pair<uint32_t, uint32_t>>
      pairs;  // (true strand, estimate strand) per matched true sample
  for (size_t i = 0; i < nearest.size(); ++i) {
    if (nearest[i] >= 0)
      pairs.emplace_back(truth_sample_strand[i],
                         estimate_sample_strand[static_cast<size_t>(nearest[i])]);
  }
  std::sort(pairs.begin(), pairs.end());
  double sum = 0;
  int64_t strands = 0;
  for (size_t begin = 0; begin < pairs.size();) {
    size_t end = begin, largest = 0;
    while (end < pairs.size() && pairs[end].first == pairs[begin].first) {
      size_t run = end;
      while (run < pairs.size() && pairs[run] == pairs[end]) ++run;
      largest = std::max(largest, run - end);
      end = run;
    }
    sum += static_cast<double>(largest) / static_cast<double>(end - begin);
    ++strands;
    begin = end;
  }
  out->consistency_strands = strands;
  out->consistency = strands > 0 ? sum / static_cast<double>(strands) : 0;
}

// Roots (first points) on the head's scalp: near its surface and OnScalp.
void MeasureRoots(const StrandSet& estimate, const HeadModel& head, double tolerance_mm,
                  StrandEvaluation* out) {
  int64_t on_scalp = 0;
  size_t first = 0;
  for (uint32_t count : estimate.point_counts) {
    const Eigen::Vector3d root = estimate.points_mm[first].cast<double>();
    first += count;
    if (std::abs(head.SignedDistance(root, nullptr)) <= tolerance_mm && head.OnScalp(root))
      ++on_scalp;
  }
  out->rooted_on_scalp = on_scalp;
  out->rooted_on_scalp_fraction =
      estimate.num_strands() > 0
          ? static_cast<double>(on_scalp) / static_cast<double>(estimate.num_strands())
          : 0.0;
}

nlohmann::json LengthsJson(const StrandLengthStats& s) {
  return {{"count", s.count},
          {"mean", s.mean_mm},
          {"p10", s.p10_mm},
          {"median", s.median_mm},
          {"p90", s.p90_mm}};
}

nlohmann::json MatchJson(const StrandMatchScores& s) {
  return {{"undirected", ScoresToJson(s.undirected)}, {"directed", ScoresToJson(s.directed)}};
}

}  // namespace

std::vector<MatchThreshold> StrandMatchThresholds() { return {{2, 20}, {3, 30}, {4, 40}, {4, 90}}; }

Status StrandEvalOptions::Check() const {
  if (!(sample_step_mm > 0) || !std::isfinite(sample_step_mm))
    return InvalidArgument("strand evaluation: sample_step_mm must be a positive number of mm");
  if (!(root_tolerance_mm >= 0) || !std::isfinite(root_tolerance_mm))
    return InvalidArgument(
        "strand evaluation: root_tolerance_mm must be a number of mm, 0 or more");
  if (threads < 1) return InvalidArgument("strand evaluation: threads must be at least 1");
  return Status::Ok();
}

Result<StrandEvaluation> EvaluateStrands(const StrandSet& estimate_in_truth_frame,
                                         const StrandSet& truth,
                                         const std::vector<uint8_t>& truth_sample_visible,
                                         const HeadModel* true_head,
                                         const StrandEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  std::vector<uint32_t> truth_sample_strand;
  const std::vector<OrientedSample> truth_samples =
      SampleStrands(truth, options.sample_step_mm, &truth_sample_strand);
  return EvaluateStrands(estimate_in_truth_frame, truth, truth_samples, truth_sample_strand,
                         truth_sample_visible, true_head, options);
}

Result<StrandEvaluation> EvaluateStrands(const StrandSet& estimate_in_truth_frame,
                                         const StrandSet& truth,
                                         const std::vector<OrientedSample>& truth_samples,
                                         const std::vector<uint32_t>& truth_sample_strand,
                                         const std::vector<uint8_t>& truth_sample_visible,
                                         const HeadModel* true_head,
                                         const StrandEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const StrandSet& estimate = estimate_in_truth_frame;
  if (const Status s = estimate.Check(); !s.ok())
    return InvalidArgument("reconstructed strands: " + s.message());
  if (const Status s = truth.Check(); !s.ok())
    return InvalidArgument("true strands: " + s.message());
  if (truth_sample_strand.size() != truth_samples.size())
    return InvalidArgument("strand evaluation: " + std::to_string(truth_sample_strand.size()) +
                           " strand indices for " + std::to_string(truth_samples.size()) +
                           " true samples");
  for (uint32_t k : truth_sample_strand) {
    if (k >= truth.num_strands())
      return InvalidArgument("strand evaluation: a true sample's strand " + std::to_string(k) +
                             " is not among the " + std::to_string(truth.num_strands()) +
                             " true strands");
  }
  const bool with_visible = !truth_sample_visible.empty();
  if (with_visible && truth_sample_visible.size() != truth_samples.size())
    return InvalidArgument("strand evaluation: the visible-surface mask has " +
                           std::to_string(truth_sample_visible.size()) + " flags for " +
                           std::to_string(truth_samples.size()) +
                           " true samples (one per sample of the truth every " +
                           std::to_string(options.sample_step_mm) + " mm)");

  StrandEvaluation out;
  out.sample_step_mm = options.sample_step_mm;
  std::vector<uint32_t> estimate_sample_strand;
  const std::vector<OrientedSample> samples =
      SampleStrands(estimate, options.sample_step_mm, &estimate_sample_strand);
  out.strands = static_cast<int64_t>(estimate.num_strands());
  out.samples = static_cast<int64_t>(samples.size());
  out.truth_strands = static_cast<int64_t>(truth.num_strands());
  out.truth_samples = static_cast<int64_t>(truth_samples.size());

  const std::vector<MatchThreshold> thresholds = StrandMatchThresholds();
  for (bool directed : {false, true}) {
    const SampleMatchOptions match{.directed = directed, .threads = options.threads};
    SubsetMatchScores scores =
        MatchSamplesAndSubset(samples, truth_samples, truth_sample_visible, thresholds, match);
    (directed ? out.all.directed : out.all.undirected) = std::move(scores.all);
    if (with_visible) {
      (directed ? out.visible.directed : out.visible.undirected) = std::move(scores.subset);
      out.visible_truth_samples = scores.subset_size;
    }
  }

  const std::vector<int64_t> nearest =
      NearestMatches(samples, truth_samples, kStrandConsistencyThreshold,
                     {.directed = false, .threads = options.threads});
  MeasureConsistency(nearest, truth_sample_strand, estimate_sample_strand, &out);

  out.root_tolerance_mm = options.root_tolerance_mm;
  if (true_head != nullptr) MeasureRoots(estimate, *true_head, options.root_tolerance_mm, &out);
  out.lengths = LengthStats(estimate);
  out.truth_lengths = LengthStats(truth);
  return out;
}

nlohmann::json StrandEvaluation::ToJson() const {
  nlohmann::json j;
  j["sample_step_mm"] = sample_step_mm;
  j["strands"] = strands;
  j["samples"] = samples;
  j["truth_strands"] = truth_strands;
  j["truth_samples"] = truth_samples;
  j["visible_truth_samples"] =
      visible_truth_samples ? nlohmann::json(*visible_truth_samples) : nlohmann::json(nullptr);
  j["all_strands"] = MatchJson(all);
  j["visible_surface"] = visible_truth_samples ? MatchJson(visible) : nlohmann::json(nullptr);
  j["consistency"] = {{"mean", consistency},
                      {"true_strands", consistency_strands},
                      {"distance_mm", kStrandConsistencyThreshold.distance_mm},
                      {"angle_deg", kStrandConsistencyThreshold.angle_deg}};
  if (rooted_on_scalp_fraction) {
    j["rooted_on_scalp"] = {{"fraction", *rooted_on_scalp_fraction},
                            {"strands", rooted_on_scalp},
                            {"tolerance_mm", root_tolerance_mm}};
  } else {
    j["rooted_on_scalp"] = nullptr;
  }
  j["lengths_mm"] = {{"reconstructed", LengthsJson(lengths)},
                     {"truth", LengthsJson(truth_lengths)}};
  return j;
}

std::string StrandEvaluation::BriefReport() const {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "strands: " << strands << " reconstructed (" << samples << " samples, every "
    << sample_step_mm << " mm) against " << truth_strands << " true (" << truth_samples
    << " samples";
  if (visible_truth_samples) s << ", " << *visible_truth_samples << " on the visible surface";
  s << "); precision / recall undirected, directed in brackets\n";
  s.precision(3);
  for (size_t k = 0; k < all.undirected.size() && k < all.directed.size(); ++k) {
    const MatchScore &u = all.undirected[k], &d = all.directed[k];
    s.precision(0);
    s << "  (" << u.threshold.distance_mm << " mm, " << u.threshold.angle_deg << " deg): ";
    s.precision(3);
    s << "precision " << u.precision << " (" << d.precision << ")";
    if (k < visible.undirected.size() && k < visible.directed.size())
      s << ", visible-surface recall " << visible.undirected[k].recall << " ("
        << visible.directed[k].recall << ")";
    s << ", all-strands recall " << u.recall << " (" << d.recall << ")\n";
  }
  s << "  consistency " << consistency << " (mean over " << consistency_strands
    << " true strands with a sample matched";
  s.precision(0);
  s << " at " << kStrandConsistencyThreshold.distance_mm << " mm, "
    << kStrandConsistencyThreshold.angle_deg << " deg)\n";
  s.precision(1);
  if (rooted_on_scalp_fraction) {
    s << "  roots on the scalp: " << 100 * *rooted_on_scalp_fraction
      << " % of reconstructed strands (" << rooted_on_scalp << ", within " << root_tolerance_mm
      << " mm of the head)\n";
  } else {
    s << "  roots on the scalp: not scored (no true head)\n";
  }
  const auto line = [&](const char* name, const StrandLengthStats& l) {
    s << "  " << name << " lengths: mean " << l.mean_mm << " mm, p10 " << l.p10_mm << ", median "
      << l.median_mm << ", p90 " << l.p90_mm << " (" << l.count << " strands)\n";
  };
  line("reconstructed", lengths);
  line("true", truth_lengths);
  return s.str();
}

Result<TruthConsistencyReference> ConsistencyOfTruthSubset(const StrandSet& truth, int64_t strands,
                                                           const StrandEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  if (const Status s = truth.Check(); !s.ok())
    return InvalidArgument("true strands: " + s.message());
  if (strands < 1) return InvalidArgument("consistency reference: strands must be at least 1");
  const int64_t every = std::max<int64_t>(
      2, std::llround(static_cast<double>(truth.num_strands()) / static_cast<double>(strands)));
  std::vector<uint32_t> sample_strand;
  const std::vector<OrientedSample> samples =
      SampleStrands(truth, options.sample_step_mm, &sample_strand);
  std::vector<OrientedSample> kept, others;
  std::vector<uint32_t> kept_strand, other_strand;
  for (size_t i = 0; i < samples.size(); ++i) {
    const bool keep = sample_strand[i] % every == 0;
    (keep ? kept : others).push_back(samples[i]);
    (keep ? kept_strand : other_strand).push_back(sample_strand[i]);
  }
  const std::vector<int64_t> nearest = NearestMatches(
      kept, others, kStrandConsistencyThreshold, {.directed = false, .threads = options.threads});
  StrandEvaluation scored;
  MeasureConsistency(nearest, other_strand, kept_strand, &scored);
  TruthConsistencyReference out;
  out.consistency = scored.consistency;
  out.scored_strands = scored.consistency_strands;
  out.kept_strands = (static_cast<int64_t>(truth.num_strands()) + every - 1) / every;
  return out;
}

}  // namespace hairrig
