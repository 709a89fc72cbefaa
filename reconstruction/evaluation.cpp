#include "reconstruction/evaluation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <vector>

#include "core/statistics.h"

namespace hairrig {

Result<OrientationAccuracy> MeasureOrientation(const OrientationMap& map, const cv::Mat& truth_deg,
                                               const cv::Mat& truth_hair, double min_confidence) {
  if (truth_deg.type() != CV_32F || truth_hair.type() != CV_8U ||
      truth_deg.size() != map.angle_deg.size() || truth_hair.size() != map.angle_deg.size()) {
    return InvalidArgument(
        "orientation truth must be CV_32F angles and a CV_8U mask of the map's size");
  }
  OrientationAccuracy a;
  std::vector<double> errors;
  for (int y = 0; y < truth_deg.rows; ++y) {
    for (int x = 0; x < truth_deg.cols; ++x) {
      const float truth = truth_deg.at<float>(y, x);
      if (truth_hair.at<uint8_t>(y, x) == 0 || !std::isfinite(truth)) continue;
      ++a.hair_pixels;
      const float angle = map.angle_deg(y, x);
      if (!std::isfinite(angle) || map.confidence(y, x) < min_confidence) continue;
      errors.push_back(OrientationDifferenceDeg(angle, truth));
    }
  }
  a.kept_pixels = static_cast<int>(errors.size());
  a.kept_fraction = a.hair_pixels > 0 ? static_cast<double>(a.kept_pixels) / a.hair_pixels : 0;
  a.median_error_deg = Quantile(errors, 0.5);
  a.p90_error_deg = Quantile(errors, 0.9);
  a.mean_error_deg = errors.empty() ? 0
                                    : std::accumulate(errors.begin(), errors.end(), 0.0) /
                                          static_cast<double>(errors.size());
  return a;
}

Result<double> MaskIoU(const cv::Mat& mask, const cv::Mat& truth_mask) {
  if (mask.size() != truth_mask.size() || mask.type() != CV_8U || truth_mask.type() != CV_8U) {
    return InvalidArgument("mask IoU: the masks must be 8-bit and of one size");
  }
  const cv::Mat a = mask != 0;
  const cv::Mat b = truth_mask != 0;
  const int both = cv::countNonZero(a & b);
  const int either = cv::countNonZero(a | b);
  return either == 0 ? 1.0 : static_cast<double>(both) / either;
}

}  // namespace hairrig
