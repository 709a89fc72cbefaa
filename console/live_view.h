// The console's live view: a low-latency preview of each camera, downscaled,
// a few frames per second, with the exposure statistics an operator frames and
// exposes by. While a capture runs the cameras belong to it, and each
// camera's preview is its newest stored frame instead (Offer).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "console/event_hub.h"
#include "console/preview_image.h"
#include "drivers/camera.h"

namespace hairrig {

struct LiveViewOptions {
  double fps = 5;          // frames per second per camera, at most
  int max_width_px = 480;  // previews are scaled down to this width
  // A frame not received this long after its trigger (wall seconds, beyond
  // the exposure) counts as lost; the camera is triggered again.
  double frame_timeout_s = 5;

  // InvalidArgument naming the field: fps outside (0, 30], max_width_px
  // outside [64, 4096], a frame_timeout_s that is not finite and positive.
  Status Check() const;
};

struct LivePreview {
  uint64_t seq = 0;  // per camera, from 1
  std::vector<uint8_t> jpeg;
  ExposureStats stats;
  double fps = 0;      // measured over the last frames
  std::string source;  // "live" or "capture"
};

// Thread-safe. Cameras are not owned: they must outlive Stop().
class LiveView {
 public:
  LiveView(EventHub& events, LiveViewOptions options) : events_(events), options_(options) {}
  ~LiveView() { Stop(); }
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  // One grabbing thread per camera (opened, ready), at most options.fps each,
  // with `settings` and the camera's overrides (SetExposure): frames of the
  // camera's live-view stream (Camera::CapturePreview: a DSLR's shutter does
  // not fire), or for a camera without one, software-triggered frames. A
  // camera that faults is left alone until Start is called again (the
  // console's reconnect does).
  void Start(const std::vector<Camera*>& cameras, const CaptureSettings& settings);
  // Stops the threads and disarms their cameras; returns once no thread uses a camera.
  void Stop();
  bool running() const { return running_.load(); }

  // Live-view exposure and gain of a camera; applied at its next frame.
  void SetExposure(const std::string& camera_name, double exposure_s, double gain_db);
  // The settings a camera's live view uses (the plan's unless overridden).
  std::pair<double, double> ExposureOf(const std::string& camera_name) const;

  // Makes `image` (8-bit BGR or mono) the camera's newest preview, published
  // as a "preview" event: the grabbing threads' frames and a capture's stored frames.
  void Offer(const std::string& camera_name, const cv::Mat& image, const std::string& source);
  std::optional<LivePreview> Latest(const std::string& camera_name) const;
  // {"seq", "fps", "clipped_fraction", "dark_fraction", "histogram", "source"} or null.
  nlohmann::json PreviewJson(const std::string& camera_name) const;

 private:
  void Grab(Camera* camera);
  bool Sleep(double seconds);  // false once stopping

  EventHub& events_;
  const LiveViewOptions options_;
  CaptureSettings settings_;
  std::vector<std::thread> threads_;
  std::atomic<bool> running_{false};
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;

  mutable std::mutex mutex_;                                   // guards the maps below
  std::map<std::string, std::pair<double, double>> exposure_;  // camera -> (exposure s, gain dB)
  std::map<std::string, uint64_t> exposure_version_;
  std::map<std::string, LivePreview> latest_;
  std::map<std::string, int64_t> last_offer_ns_;
};

}  // namespace hairrig
