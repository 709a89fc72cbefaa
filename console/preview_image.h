// Small pictures for the console: live-view frames and thumbnails.
#pragma once

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/status.h"

namespace hairrig {

// `image` scaled down (area averaging) to at most `max_width_px` wide; never
// up; the image itself when it is narrow enough.
cv::Mat DownscaleForPreview(const cv::Mat& image, int max_width_px);

// `image` (8-bit, 1 or 3 channels BGR) scaled down to at most `max_width_px`
// wide (never up), as a JPEG. Internal if encoding fails.
Result<std::vector<uint8_t>> EncodePreviewJpeg(const cv::Mat& image, int max_width_px,
                                               int quality = 80);

struct ExposureStats {
  std::vector<int> histogram;   // 64 bins of luminance (0-255, 4 levels a bin), pixel counts
  double clipped_fraction = 0;  // share of pixels with a channel at 255 (over-exposed)
  double dark_fraction = 0;     // share of pixels with luminance below 4 (under-exposed)
};
// Of an 8-bit image (1 or 3 channels BGR); luminance is Rec. 601's.
ExposureStats MeasureExposure(const cv::Mat& image);

}  // namespace hairrig
