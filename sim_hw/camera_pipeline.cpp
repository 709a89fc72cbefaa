#include "sim_hw/camera_pipeline.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/string_format.h"

namespace hairrig {

bool CameraPipeline::Identity() const {
  return iso == 100 && exposure_ev == 0 && white_balance == Eigen::Vector3d(1, 1, 1) && !bayer &&
         tone == Tone::kLinear && jpeg_quality == 0 && f_number == 0 && lens_blur_px == 0 &&
         render_grain_sd == 0;
}

Status CameraPipeline::Check() const {
  const auto range = [](const char* field, double value, double lo, double hi) {
    if (value >= lo && value <= hi) return Status::Ok();
    return InvalidArgument(
        StringPrintf("camera_pipeline.%s must lie in [%g, %g], got %g", field, lo, hi, value));
  };
  HR_RETURN_IF_ERROR(range("iso", iso, 25, 102400));
  HR_RETURN_IF_ERROR(range("exposure_ev", exposure_ev, -6, 6));
  for (int c = 0; c < 3; ++c) HR_RETURN_IF_ERROR(range("white_balance", white_balance[c], 0.1, 10));
  HR_RETURN_IF_ERROR(range("jpeg_quality", jpeg_quality, 0, 100));
  if (f_number != 0) HR_RETURN_IF_ERROR(range("f_number", f_number, 0.7, 64));
  HR_RETURN_IF_ERROR(range("focus_mm", focus_mm, 0, 1e6));
  HR_RETURN_IF_ERROR(range("pixel_um", pixel_um, 0.5, 100));
  HR_RETURN_IF_ERROR(range("lens_blur_px", lens_blur_px, 0, 20));
  HR_RETURN_IF_ERROR(range("render_grain_sd", render_grain_sd, 0, 2));
  return Status::Ok();
}

double CircleOfConfusionPx(const CameraPipeline& pipeline, double focal_px, double focus_mm,
                           double z_mm) {
  if (pipeline.f_number <= 0) return 0;
  const double f_mm = focal_px * 1e-3 * pipeline.pixel_um;
  if (focus_mm <= f_mm) return 0;
  const double aperture_mm = f_mm / pipeline.f_number;
  const double off_focus = std::isfinite(z_mm) ? std::abs(z_mm - focus_mm) / z_mm : 1.0;
  const double on_sensor_mm = aperture_mm * f_mm / (focus_mm - f_mm) * off_focus;
  return on_sensor_mm / (1e-3 * pipeline.pixel_um);
}

namespace {

// Blur levels (Gaussian sigma, px) the defocused image is gathered from.
constexpr std::array<float, 12> kBlurLevels = {0, 0.5f, 1, 1.5f, 2, 3, 4.5, 6, 8.5f, 12, 16.5f, 24};

cv::Mat3f Blurred(const cv::Mat3f& radiance, float sigma) {
  if (sigma <= 0) return radiance;
  cv::Mat3f out;
  cv::GaussianBlur(radiance, out, cv::Size(), sigma, sigma, cv::BORDER_REFLECT);
  return out;
}

}  // namespace

cv::Mat3f DefocusRadiance(const cv::Mat3f& radiance, const cv::Mat1f& depth_mm,
                          const CameraPipeline& pipeline, double focal_px, double focus_mm) {
  if (pipeline.f_number <= 0 && pipeline.lens_blur_px <= 0) return radiance;
  // Per pixel, the Gaussian's sigma: half the circle of confusion, with the lens' own blur.
  cv::Mat1f sigma(radiance.size());
  float max_sigma = 0;
  for (int y = 0; y < radiance.rows; ++y) {
    for (int x = 0; x < radiance.cols; ++x) {
      const double coc = CircleOfConfusionPx(pipeline, focal_px, focus_mm, depth_mm(y, x));
      const double s = std::hypot(0.5 * coc, pipeline.lens_blur_px);
      sigma(y, x) = std::min(static_cast<float>(s), kBlurLevels.back());
      max_sigma = std::max(max_sigma, sigma(y, x));
    }
  }
  std::vector<cv::Mat3f> stack;
  for (float level : kBlurLevels) {
    stack.push_back(Blurred(radiance, level));
    if (level >= max_sigma) break;
  }
  cv::Mat3f out(radiance.size());
  for (int y = 0; y < radiance.rows; ++y) {
    for (int x = 0; x < radiance.cols; ++x) {
      const float s = sigma(y, x);
      size_t k = 1;
      while (k + 1 < stack.size() && kBlurLevels[k] < s) ++k;
      if (stack.size() == 1) {
        out(y, x) = stack[0](y, x);
        continue;
      }
      const float lo = kBlurLevels[k - 1], hi = kBlurLevels[k];
      const float w = std::clamp((s - lo) / (hi - lo), 0.0f, 1.0f);
      out(y, x) = stack[k - 1](y, x) * (1 - w) + stack[k](y, x) * w;
    }
  }
  return out;
}

namespace {

// The sRGB transfer curve on 0..255 DN, tabulated.
float SrgbDn(float dn) {
  static const std::vector<float> table = [] {
    std::vector<float> t(4097);
    for (size_t i = 0; i < t.size(); ++i) {
      const double v = static_cast<double>(i) / 4096.0;
      const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
      t[i] = static_cast<float>(255.0 * s);
    }
    return t;
  }();
  const float g = std::clamp(dn / 255.0f, 0.0f, 1.0f) * 4096.0f;
  const size_t i = std::min(static_cast<size_t>(g), size_t{4095});
  return table[i] + (g - static_cast<float>(i)) * (table[i + 1] - table[i]);
}

// Bilinear demosaicing of the RGGB mosaic in `sensor_dn` (the sampled channel
// of each photosite), in 16 bits.
cv::Mat3f Demosaic(const cv::Mat3f& sensor_dn) {
  cv::Mat1w mosaic(sensor_dn.size());
  for (int y = 0; y < sensor_dn.rows; ++y) {
    for (int x = 0; x < sensor_dn.cols; ++x) {
      const float dn = sensor_dn(y, x)[BayerChannel(x, y)];
      mosaic(y, x) = static_cast<uint16_t>(std::clamp(std::lround(dn * 256.0f), 0L, 65535L));
    }
  }
  // OpenCV names a mosaic by its second row's second and third pixels: B, G for RGGB.
  cv::Mat colour;
  cv::demosaicing(mosaic, colour, cv::COLOR_BayerBG2BGR);
  cv::Mat3f out;
  colour.convertTo(out, CV_32FC3, 1.0 / 256.0);
  return out;
}

}  // namespace

cv::Mat DevelopImage(const cv::Mat3f& sensor_dn, const CameraPipeline& pipeline) {
  const cv::Mat3f linear = pipeline.bayer ? Demosaic(sensor_dn) : sensor_dn;
  // Gains in BGR order.
  const std::array<float, 3> gain = {static_cast<float>(pipeline.white_balance.z()),
                                     static_cast<float>(pipeline.white_balance.y()),
                                     static_cast<float>(pipeline.white_balance.x())};
  const bool srgb = pipeline.tone == CameraPipeline::Tone::kSrgb;
  cv::Mat image(linear.rows, linear.cols, CV_8UC3);
  for (int y = 0; y < linear.rows; ++y) {
    const cv::Vec3f* in = linear.ptr<cv::Vec3f>(y);
    cv::Vec3b* out = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < linear.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        float dn = std::min(in[x][c] * gain[static_cast<size_t>(c)], 255.0f);
        if (srgb) dn = SrgbDn(dn);
        out[x][c] = static_cast<uint8_t>(std::clamp(std::lround(dn), 0L, 255L));
      }
    }
  }
  if (pipeline.jpeg_quality <= 0) return image;
  std::vector<uint8_t> bytes;
  cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, pipeline.jpeg_quality});
  return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

}  // namespace hairrig
