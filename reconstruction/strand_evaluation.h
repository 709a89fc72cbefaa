// The strand protocol of `hairrig eval reconstruction` (docs/design.md section 6):
// reconstructed strands against the true strands of a simulated capture.
//
//   samples      both strand sets sampled along their length (point_evaluation.h's
//                SampleStrands) and matched at StrandMatchThresholds(): precision,
//                recall and F1, undirected (d and -d the same) and directed (the
//                root-to-tip sign counts); recall against every true sample and
//                against the visible surface (true samples seen by >= 2
//                cameras, a mask the caller gives); one precision for both.
//   consistency  per true strand, the largest share of its matched samples
//                (kStrandConsistencyThreshold, undirected, each true sample
//                matched to its nearest estimate sample) that come from one
//                reconstructed strand; the mean over true strands with at
//                least one matched sample. 1: every true strand is reproduced
//                by one strand; 1/k: it is cut into k equal pieces.
//   roots        the share of reconstructed strands whose root (first point)
//                lies on the true head's scalp: within root_tolerance_mm of
//                its surface and above the hairline, off the parting
//                (HeadModel::OnScalp; a head without a scalp region: anywhere).
//   lengths      count, mean and quantiles of the strand lengths of both sets.
//
// Frames: both strand sets in one frame, mm (evaluation maps the
// reconstruction into the truth's, the turntable frame); the head in that frame.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "core/strands.h"
#include "reconstruction/point_evaluation.h"

namespace hairrig {

// (2 mm, 20 deg), (3 mm, 30 deg), (4 mm, 40 deg), (4 mm, 90 deg).
std::vector<MatchThreshold> StrandMatchThresholds();
// The threshold at which the strand consistency matches samples (undirected).
inline constexpr MatchThreshold kStrandConsistencyThreshold{3, 30};

struct StrandEvalOptions {
  double sample_step_mm = 1.0;  // both sets sampled at most this far apart along a strand (> 0)
  double root_tolerance_mm =
      3.0;  // a root within this of the head's surface (|signed distance| <=) is on it (>= 0)
  int threads = 2;  // at least 1

  // InvalidArgument naming the field for a value out of range (or NaN).
  Status Check() const;
};

// Distribution of strand lengths (mm, along the polyline); quantiles as
// core/statistics.h's Quantile (no interpolation). All 0 for no strands.
struct StrandLengthStats {
  int64_t count = 0;
  double mean_mm = 0, p10_mm = 0, median_mm = 0, p90_mm = 0;
};

// One set of scores, undirected and directed, per StrandMatchThresholds() in order.
struct StrandMatchScores {
  std::vector<MatchScore> undirected;
  std::vector<MatchScore> directed;
};

struct StrandEvaluation {
  double sample_step_mm = 0;                     // as evaluated
  int64_t strands = 0, samples = 0;              // reconstructed
  int64_t truth_strands = 0, truth_samples = 0;  // true
  // True samples on the visible surface; nullopt when no mask was given (and
  // `visible` is then empty).
  std::optional<int64_t> visible_truth_samples;
  StrandMatchScores all;            // recall against every true sample
  StrandMatchScores visible;        // recall against the visible surface; precision as `all`'s
  double consistency = 0;           // mean over consistency_strands (0 when there are none)
  int64_t consistency_strands = 0;  // true strands with at least one matched sample
  // Share of reconstructed strands rooted on the scalp and their number;
  // nullopt without a true head (not scored, which is not 0).
  std::optional<double> rooted_on_scalp_fraction;
  int64_t rooted_on_scalp = 0;
  double root_tolerance_mm = 0;
  StrandLengthStats lengths, truth_lengths;

  // {"strands", "samples", "truth_strands", "truth_samples", "visible_truth_samples",
  //  "all_strands": {"undirected": [...], "directed": [...]}, "visible_surface": {...} or null,
  //  "consistency": {...}, "rooted_on_scalp": {...} or null, "lengths_mm": {"reconstructed",
  //  "truth"}};
  // scores as point_evaluation.h's ScoresToJson.
  nlohmann::json ToJson() const;
  // A few lines: the counts, one line per threshold, consistency, roots, lengths.
  std::string BriefReport() const;
};

// Scores `estimate_in_truth_frame` against `truth`. `truth_sample_visible` has
// one flag per sample of SampleStrands(truth, options.sample_step_mm) (non-zero:
// on the visible surface), or is empty for no visible-surface scores.
// `true_head` may be null (no root scores). Either set may be empty (its
// scores are then 0). InvalidArgument for options that fail Check(), a strand
// set that fails StrandSet::Check() (naming which), or a mask of another size.
// Time: a few MatchSamples runs over the samples (seconds for millions of samples).
Result<StrandEvaluation> EvaluateStrands(const StrandSet& estimate_in_truth_frame,
                                         const StrandSet& truth,
                                         const std::vector<uint8_t>& truth_sample_visible,
                                         const HeadModel* true_head,
                                         const StrandEvalOptions& options);

// The same with the truth already sampled, for a caller that samples it once
// for other scores as well: `truth_samples` and `truth_sample_strand` must be
// SampleStrands(truth, options.sample_step_mm, &truth_sample_strand) (checked:
// sizes, and strand indices within `truth`).
Result<StrandEvaluation> EvaluateStrands(const StrandSet& estimate_in_truth_frame,
                                         const StrandSet& truth,
                                         const std::vector<OrientedSample>& truth_samples,
                                         const std::vector<uint32_t>& truth_sample_strand,
                                         const std::vector<uint8_t>& truth_sample_visible,
                                         const HeadModel* true_head,
                                         const StrandEvalOptions& options);

// The consistency a reconstruction as faithful as the truth itself scores
// at about `strands` strands: every k-th true strand (k = the true count /
// `strands`, rounded, at least 2, so at most half the truth is kept) taken as
// the reconstruction, and the other true strands scored against it as
// EvaluateStrands scores consistency. Neighbouring true strands weave around
// one another, so even this stays under 1, and it falls as more strands are
// kept: the reference a reconstruction's consistency is read against.
struct TruthConsistencyReference {
  double consistency = 0;      // mean over scored_strands; 0 when none has a match
  int64_t kept_strands = 0;    // true strands taken as the reconstruction
  int64_t scored_strands = 0;  // the other true strands with a matched sample
};
// InvalidArgument for bad options, an invalid truth or `strands` < 1.
Result<TruthConsistencyReference> ConsistencyOfTruthSubset(const StrandSet& truth, int64_t strands,
                                                           const StrandEvalOptions& options);

}  // namespace hairrig
