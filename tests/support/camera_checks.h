// Test helpers for camera backends: one software-triggered shot, arming for
// a line trigger, waiting for a condition, and the PSNR between a delivered
// frame and the world rendered directly. Header-only.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <thread>

#include "drivers/camera.h"

namespace hairrig_test {

// How long a camera test waits for a frame: a liveness bound, not a speed
// check (sanitizer builds render slowly).
constexpr std::chrono::milliseconds kFrameWait{20000};

// Polls `done` until it holds; false after kFrameWait. For a state a
// simulator reaches in its own thread, which a busy machine makes late.
inline bool WaitUntil(const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + kFrameWait;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

// Configure, Arm, SoftwareTrigger, WaitFrame, Disarm.
inline hairrig::Result<hairrig::Frame> ShootOnce(hairrig::Camera& camera,
                                                 hairrig::PixelFormat format,
                                                 double exposure_s = 0.02, double gain_db = 0) {
  hairrig::CaptureSettings s;
  s.format = format;
  s.exposure_s = exposure_s;
  s.gain_db = gain_db;
  HR_RETURN_IF_ERROR(camera.Configure(s));
  HR_RETURN_IF_ERROR(camera.Arm());
  HR_RETURN_IF_ERROR(camera.SoftwareTrigger());
  auto frame = camera.WaitFrame(kFrameWait);
  (void)camera.Disarm();
  return frame;
}

// Configure for a trigger on `line` (TriggerSource::kLine) in `format`, then Arm.
inline hairrig::Status ArmOnLine(hairrig::Camera& camera, const std::string& line,
                                 hairrig::PixelFormat format = hairrig::PixelFormat::kRgb8) {
  hairrig::CaptureSettings s;
  s.format = format;
  s.trigger = hairrig::TriggerSource::kLine;
  s.trigger_line = line;
  HR_RETURN_IF_ERROR(camera.Configure(s));
  return camera.Arm();
}

// Peak signal-to-noise ratio of two 8-bit images of one size, in dB.
inline double Psnr(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return 10.0 * std::log10(255.0 * 255.0 / std::max(mse, 1e-12));
}

}  // namespace hairrig_test
