#include "console/preview_image.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace hairrig {

cv::Mat DownscaleForPreview(const cv::Mat& image, int max_width_px) {
  if (image.empty() || max_width_px <= 0 || image.cols <= max_width_px) return image;
  const double scale = static_cast<double>(max_width_px) / image.cols;
  cv::Mat small;
  cv::resize(image, small, cv::Size(), scale, scale, cv::INTER_AREA);
  return small;
}

Result<std::vector<uint8_t>> EncodePreviewJpeg(const cv::Mat& image, int max_width_px,
                                               int quality) {
  if (image.empty() || image.depth() != CV_8U) return InvalidArgument("preview: no 8-bit image");
  const cv::Mat small = DownscaleForPreview(image, max_width_px);
  std::vector<uint8_t> jpeg;
  if (!cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality}))
    return Internal("preview: JPEG encoding failed");
  return jpeg;
}

ExposureStats MeasureExposure(const cv::Mat& image) {
  ExposureStats stats;
  stats.histogram.assign(64, 0);
  if (image.empty() || image.depth() != CV_8U) return stats;
  cv::Mat gray;
  if (image.channels() == 3)
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  else
    gray = image;
  cv::Mat peak;  // the brightest channel of each pixel
  if (image.channels() == 3) {
    std::vector<cv::Mat> planes;
    cv::split(image, planes);
    peak = cv::max(cv::max(planes[0], planes[1]), planes[2]);
  } else {
    peak = image;
  }
  int64_t clipped = 0, dark = 0;
  for (int y = 0; y < gray.rows; ++y) {
    const uint8_t* g = gray.ptr<uint8_t>(y);
    const uint8_t* p = peak.ptr<uint8_t>(y);
    for (int x = 0; x < gray.cols; ++x) {
      ++stats.histogram[g[x] >> 2];
      clipped += p[x] == 255;
      dark += g[x] < 4;
    }
  }
  const double pixels = static_cast<double>(gray.total());
  stats.clipped_fraction = static_cast<double>(clipped) / pixels;
  stats.dark_fraction = static_cast<double>(dark) / pixels;
  return stats;
}

}  // namespace hairrig
