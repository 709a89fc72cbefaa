#include "drivers/frame_image.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

namespace hairrig {

Result<cv::Mat> FrameImage(const Frame& frame) {
  if (frame.format == PixelFormat::kEncoded) {
    cv::Mat image = cv::imdecode(frame.data, cv::IMREAD_UNCHANGED);
    if (image.empty())
      return CorruptData("the " + frame.encoding + " file does not decode (" +
                         std::to_string(frame.data.size()) + " bytes)");
    return image;
  }
  if (frame.width_px <= 0 || frame.height_px <= 0 || frame.data.size() != frame.ExpectedBytes()) {
    return CorruptData(std::to_string(frame.data.size()) + " bytes for a " +
                       std::to_string(frame.width_px) + "x" + std::to_string(frame.height_px) +
                       " " + PixelFormatName(frame.format) + " frame (expected " +
                       std::to_string(frame.ExpectedBytes()) + ")");
  }
  const int channels = BytesPerPixel(frame.format);
  const cv::Mat raw(frame.height_px, frame.width_px, channels == 3 ? CV_8UC3 : CV_8UC1,
                    const_cast<uint8_t*>(frame.data.data()));
  cv::Mat image;
  if (frame.format == PixelFormat::kRgb8)
    cv::cvtColor(raw, image, cv::COLOR_RGB2BGR);
  else
    image = raw.clone();
  return image;
}

}  // namespace hairrig
