// Pieces every camera backend needs: the steady clock frames are stamped
// with, the exposure-range check of Configure, and the trigger times frames
// are matched to.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>

#include "core/clock.h"
#include "core/status.h"

namespace hairrig {

class Camera;
class ConfigNode;
struct CameraCapabilities;

// What a real camera backend is told about the unit beyond its protocol: the
// image size to check downloads against and the nominal timings the
// capture's time budget uses. Config fields width_px, height_px, readout_s,
// download_s; `time_scale` is set by a simulated rig only.
struct CameraNominal {
  int width_px = 0;  // 0: not checked (or the sensor's, where the backend can read it)
  int height_px = 0;
  double readout_s = 0.2;
  double download_s = 1.0;
  double time_scale = 1.0;  // wall s per device s
  // Wall seconds from trigger to frame on the host: exposure + readout + download.
  double LatencyWallS(double exposure_s) const {
    return (exposure_s + readout_s + download_s) * time_scale;
  }
  // InvalidArgument naming the field for a value outside the ranges
  // ReadCameraNominal accepts, or a time_scale that is not finite and positive.
  Status Check() const;
};
// Reads the fields, keeping `defaults` for those absent; errors are recorded on `device`.
CameraNominal ReadCameraNominal(const ConfigNode& device, const CameraNominal& defaults);

// SteadyNowNs (core/clock.h) is the clock of Frame::trigger_time_ns and received_time_ns.

// OutOfRange naming the camera when `exposure_s` is outside the capabilities' range.
Status CheckExposure(const Camera& camera, const CameraCapabilities& caps, double exposure_s);

// The trigger time of each frame, in trigger order: software triggers and
// line pulses are recorded when sent, and each frame takes the oldest. A frame
// with no recorded trigger (a pulse the camera saw but the host did not send)
// is dated back from its arrival by the nominal latency. Thread-safe, with a
// lock of its own, so that noting a pulse never waits for a download.
class TriggerTimes {
 public:
  void Clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_ns_.clear();
  }
  void Sent(int64_t t_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_ns_.push_back(t_ns);
  }
  // `latency_wall_s`: exposure + readout + download, in wall seconds.
  int64_t ForFrame(int64_t received_ns, double latency_wall_s) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (sent_ns_.empty()) return received_ns - static_cast<int64_t>(latency_wall_s * 1e9);
    const int64_t t = sent_ns_.front();
    sent_ns_.pop_front();
    return t;
  }

 private:
  std::mutex mutex_;
  std::deque<int64_t> sent_ns_;
};

}  // namespace hairrig
