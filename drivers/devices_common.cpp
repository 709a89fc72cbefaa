#include <cmath>

#include "drivers/camera.h"
#include "drivers/turntable.h"

namespace hairrig {

Status Turntable::MoveTo(double target_deg, const MotionProfile& profile, std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(StartMove(target_deg, profile));
  return WaitInPosition(timeout);
}

double MoveDurationS(double distance_deg, const MotionProfile& profile) {
  const double d = std::abs(distance_deg);
  const double t_acc = profile.speed_deg_s / profile.accel_deg_s2;
  if (d < profile.speed_deg_s * t_acc) return 2 * std::sqrt(d / profile.accel_deg_s2);
  return d / profile.speed_deg_s + t_acc;
}

const char* PixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8: return "Mono8";
    case PixelFormat::kRgb8: return "RGB8";
    case PixelFormat::kBgr8: return "BGR8";
    case PixelFormat::kBayerRG8: return "BayerRG8";
    case PixelFormat::kEncoded: return "Encoded";
  }
  return "?";
}

int BytesPerPixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
    case PixelFormat::kBayerRG8: return 1;
    case PixelFormat::kRgb8:
    case PixelFormat::kBgr8: return 3;
    case PixelFormat::kEncoded: return 0;
  }
  return 0;
}

size_t Frame::ExpectedBytes() const {
  return static_cast<size_t>(width_px) * static_cast<size_t>(height_px) * static_cast<size_t>(BytesPerPixel(format));
}

}  // namespace hairrig
