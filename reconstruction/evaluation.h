// Accuracy of the reconstruction's stages against per-pixel ground truth
// (the simulated rig's maps, docs/design.md section 3), computed once here for
// `hairrig eval reconstruction`, the tests and the benchmarks.
#pragma once

#include <opencv2/core/mat.hpp>

#include "reconstruction/orientation_map.h"

namespace hairrig {

struct OrientationAccuracy {
  int hair_pixels = 0;          // pixels the truth calls hair (with a strand direction)
  int kept_pixels = 0;          // ... of which the map keeps (confidence >= the threshold)
  double kept_fraction = 0;     // kept / hair
  double median_error_deg = 0;  // unsigned angle error over the kept pixels
  double p90_error_deg = 0;
  double mean_error_deg = 0;
};

// `truth_deg`: CV_32F, the true 2D direction in [0, 180), NaN where no strand;
// `truth_hair`: CV_8U, non-zero on the pixels to score (e.g. label == hair).
// A map pixel is kept where its confidence is at least `min_confidence` and
// its angle is known. Sizes must agree (InvalidArgument otherwise).
Result<OrientationAccuracy> MeasureOrientation(const OrientationMap& map, const cv::Mat& truth_deg,
                                               const cv::Mat& truth_hair, double min_confidence);

// Overlap of a hair mask with the true one: |A and B| / |A or B| (1 when
// both are empty). Masks: CV_8U, non-zero = hair, the same size
// (InvalidArgument otherwise).
Result<double> MaskIoU(const cv::Mat& mask, const cv::Mat& truth_mask);

}  // namespace hairrig
