#include "core/contact_sheet.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace hairrig {

cv::Mat MakeContactSheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& labels,
                         int columns, int thumb_width_px) {
  if (images.empty()) return {};
  const double scale = static_cast<double>(thumb_width_px) / images[0].cols;
  const int thumb_h = static_cast<int>(std::lround(images[0].rows * scale));
  const int rows = (static_cast<int>(images.size()) + columns - 1) / columns;
  constexpr int kGap = 4;
  cv::Mat sheet(rows * (thumb_h + kGap) + kGap, columns * (thumb_width_px + kGap) + kGap, CV_8UC3,
                cv::Scalar(32, 32, 32));
  for (size_t i = 0; i < images.size(); ++i) {
    const int r = static_cast<int>(i) / columns, c = static_cast<int>(i) % columns;
    cv::Mat thumb;
    cv::resize(images[i], thumb, cv::Size(thumb_width_px, thumb_h), 0, 0, cv::INTER_AREA);
    const cv::Rect where(kGap + c * (thumb_width_px + kGap), kGap + r * (thumb_h + kGap),
                         thumb_width_px, thumb_h);
    thumb.copyTo(sheet(where));
    if (i < labels.size()) {
      cv::rectangle(sheet, cv::Rect(where.x, where.y, where.width, 22), cv::Scalar(0, 0, 0),
                    cv::FILLED);
      cv::putText(sheet, labels[i], {where.x + 4, where.y + 16}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
  }
  return sheet;
}

}  // namespace hairrig
