// Guide strands (Bao & Qi 2017, Sec. V opening): a hair model reduced to K
// guides by hierarchical clustering, each guide a real strand of its cluster.
//
// Strands are resampled to `samples` points at equal arc length from the root;
// the distance between two strands is the RMS distance of corresponding
// samples (mm). Clustering is divisive: starting from one cluster, the cluster
// that contributes most error is split in two (2-means, seeded by its two most
// distant members) until there are K clusters or the RMS distance of all
// strands to their guides is within the target. The guide of a cluster is the member
// nearest to the cluster mean.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

struct GuideOptions {
  int num_guides = 0;          // K; 0: grow until target_rms_mm is met
  double target_rms_mm = 5.0;  // used when num_guides is 0
  int samples = 16;            // resampling per strand
  int max_guides = 100000;     // safety bound when growing by target
  int kmeans_iterations = 12;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

struct GuideSelection {
  std::vector<int> guide_strands;      // strand index of each guide
  std::vector<int> cluster_of_strand;  // guide number (index into guide_strands) per strand
  double rms_error_mm = 0;             // RMS distance of strands to their guides, all strands
  double max_cluster_rms_mm = 0;
};

// Points of one strand resampled to `samples` points at equal arc length
// (root first). A strand of one point repeats it.
std::vector<Eigen::Vector3f> ResampleByArcLength(const Eigen::Vector3f* points, size_t count,
                                                 int samples);

// InvalidArgument for an empty model, bad options, or K above the strand count.
Result<GuideSelection> SelectGuides(const StrandSet& strands, const GuideOptions& options);

}  // namespace hairrig
