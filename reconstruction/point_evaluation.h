// Precision and recall of oriented samples (a point cloud, or strands sampled
// along their length) against true oriented samples, at distance and angle
// thresholds: the one implementation behind the point and strand scores of
// `hairrig eval reconstruction`, the tests and the benchmarks.
//
// Both sample sets must be in one frame, in mm (e.g. the object frame of the
// reconstruction, with the truth moved into it).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

struct OrientedSample {
  Eigen::Vector3f position_mm = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction =
      Eigen::Vector3f::Zero();  // unit (it is normalised again); may be signed
};

struct MatchThreshold {
  double distance_mm = 0;  // finite and >= 0, else the threshold matches nothing
  double angle_deg = 0;  // in [0, 180] (above 180: any direction), negative or NaN matches nothing
};

// The thresholds of the project's protocol: (1 mm, 10 deg), (2 mm, 20), (3 mm, 30), (4 mm, 40), (4
// mm, 90).
std::vector<MatchThreshold> DefaultMatchThresholds();

struct MatchScore {
  MatchThreshold threshold;
  double precision = 0, recall = 0, f1 = 0;
  int64_t matched_estimate = 0;  // estimate samples with a true sample within the threshold
  int64_t matched_truth = 0;     // true samples with an estimate sample within the threshold
};

struct SampleMatchOptions {
  bool directed =
      false;  // the sign of the direction counts (strands root to tip); else d and -d are the same
  int threads = 2;  // at least 1 is used

  // Every value is valid (threads below 1 run on one thread).
  Status Check() const { return Status::Ok(); }
};

// One score per threshold, in the order given. precision = share of
// `estimate` samples that have a `truth` sample within distance_mm (<=) whose
// direction is within angle_deg (<=; unsigned: the smaller of the angles to d
// and to -d, directed: the angle to d); recall = share of `truth` samples that
// have such an `estimate` sample; f1 their harmonic mean (0 when both are 0).
// Empty estimate: precision 0; empty truth: recall 0. A sample with a
// non-finite position, a zero or non-finite direction, or a position more than
// 2^20 times the largest distance threshold from the origin matches nothing
// but still counts in its set's size.
//
// Runs on `options.threads` threads. Time is about linear in the sizes for
// hair-like densities (millions of samples in seconds; a threshold far larger
// than the sample spacing makes it quadratic); memory is linear in the sizes
// (about 70 bytes a sample while the sets are sorted into cells, 40 after).
std::vector<MatchScore> MatchSamples(const std::vector<OrientedSample>& estimate,
                                     const std::vector<OrientedSample>& truth,
                                     const std::vector<MatchThreshold>& thresholds,
                                     const SampleMatchOptions& options);

// Recall against all true samples and against a subset of them (the visible
// surface: true samples seen by enough cameras), with one precision.
struct SubsetMatchScores {
  std::vector<MatchScore> all;  // MatchSamples(estimate, truth, ...)
  // Recall (and matched_truth) against the true samples whose flag is set;
  // precision, matched_estimate and so F1 from `all`: an estimate sample is
  // right when it lies on any true strand, seen or not. Empty when the flags
  // are not one per true sample.
  std::vector<MatchScore> subset;
  int64_t subset_size = 0;  // true samples in the subset
};
SubsetMatchScores MatchSamplesAndSubset(const std::vector<OrientedSample>& estimate,
                                        const std::vector<OrientedSample>& truth,
                                        const std::vector<uint8_t>& truth_in_subset,
                                        const std::vector<MatchThreshold>& thresholds,
                                        const SampleMatchOptions& options);

// Which estimate sample matched each true sample: per `truth` sample, the
// index in `estimate` of the nearest estimate sample (Euclidean) among those
// within `threshold` as MatchSamples counts them (distance <=, angle <=,
// directed or not by `options`), the lower index of equally near ones; -1 when
// there is none. The same grid as MatchSamples, on `options.threads` threads
// (a little more time than one threshold of MatchSamples: every candidate
// within reach is looked at); samples that match nothing there (non-finite,
// far out, no direction) are -1 or never chosen.
std::vector<int64_t> NearestMatches(const std::vector<OrientedSample>& estimate,
                                    const std::vector<OrientedSample>& truth,
                                    const MatchThreshold& threshold,
                                    const SampleMatchOptions& options);

// [{"distance_mm", "angle_deg", "precision", "recall", "f1"}, ...] in the scores' order.
nlohmann::json ScoresToJson(const std::vector<MatchScore>& scores);

// Samples along polylines (points root to tip, mm): every vertex of a strand
// and, on each segment, evenly spaced points so that consecutive samples are
// at most `step_mm` apart (`step_mm` <= 0 or non-finite: the vertices only).
// A sample's direction is its segment's unit direction root to tip; the tip
// takes its last segment's. Zero-length and non-finite segments give no
// samples; a strand of one point gives none.
std::vector<OrientedSample> SampleStrands(const std::vector<std::vector<Eigen::Vector3f>>& strands,
                                          double step_mm);
std::vector<OrientedSample> SampleStrands(const StrandSet& strands, double step_mm);
// The same samples, and in `sample_strand` (replaced; may be null) the index
// of each sample's strand in `strands`. Samples come strand after strand, so
// the indices never decrease.
std::vector<OrientedSample> SampleStrands(const StrandSet& strands, double step_mm,
                                          std::vector<uint32_t>* sample_strand);

}  // namespace hairrig
