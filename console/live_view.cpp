#include "console/live_view.h"

#include <chrono>
#include <cmath>
#include <string>

#include "core/clock.h"
#include "core/log.h"
#include "drivers/frame_image.h"

namespace hairrig {

Status LiveViewOptions::Check() const {
  if (!(fps > 0 && fps <= 30)) return InvalidArgument("fps must be in (0, 30] frames per second");
  if (max_width_px < 64 || max_width_px > 4096) {
    return InvalidArgument("max_width_px must be in [64, 4096], got " +
                           std::to_string(max_width_px));
  }
  if (!(frame_timeout_s > 0) || !std::isfinite(frame_timeout_s))
    return InvalidArgument("frame_timeout_s must be a finite positive number of seconds");
  return Status::Ok();
}

void LiveView::Start(const std::vector<Camera*>& cameras, const CaptureSettings& settings) {
  Stop();
  settings_ = settings;
  settings_.trigger = TriggerSource::kSoftware;
  settings_.trigger_line.clear();
  {
    std::lock_guard<std::mutex> lock(stop_mutex_);
    stopping_ = false;
  }
  running_ = true;
  for (Camera* camera : cameras) threads_.emplace_back([this, camera] { Grab(camera); });
}

void LiveView::Stop() {
  {
    std::lock_guard<std::mutex> lock(stop_mutex_);
    stopping_ = true;
    stop_cv_.notify_all();
  }
  for (std::thread& t : threads_) t.join();
  threads_.clear();
  running_ = false;
}

bool LiveView::Sleep(double seconds) {
  std::unique_lock<std::mutex> lock(stop_mutex_);
  stop_cv_.wait_for(lock, std::chrono::duration<double>(std::max(0.0, seconds)),
                    [this] { return stopping_; });
  return !stopping_;
}

void LiveView::SetExposure(const std::string& camera_name, double exposure_s, double gain_db) {
  std::lock_guard<std::mutex> lock(mutex_);
  exposure_[camera_name] = {exposure_s, gain_db};
  ++exposure_version_[camera_name];
}

std::pair<double, double> LiveView::ExposureOf(const std::string& camera_name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = exposure_.find(camera_name);
  if (it != exposure_.end()) return it->second;
  return {settings_.exposure_s, settings_.gain_db};
}

namespace {

// One frame: from the camera's live-view stream, or else triggered (armed).
Result<Frame> NextFrame(Camera& camera, bool stream, double wait_s) {
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(1000 * wait_s));
  if (stream) return camera.CapturePreview(timeout);
  HR_RETURN_IF_ERROR(camera.SoftwareTrigger());
  return camera.WaitFrame(timeout);
}

}  // namespace

// Offers one frame after another from the camera's live-view stream, or, for
// a camera without one, from software triggers; reconfigures when the
// operator changes the exposure. Ends at Stop() or when the camera faults.
void LiveView::Grab(Camera* camera) {
  const std::string name = camera->info().name;
  uint64_t configured_version = UINT64_MAX;
  bool stream = true;  // until the camera says it has no live-view stream
  while (Sleep(0)) {
    uint64_t version = 0;
    CaptureSettings settings = settings_;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      version = exposure_version_[name];
    }
    std::tie(settings.exposure_s, settings.gain_db) = ExposureOf(name);
    if (version != configured_version) {
      (void)camera->Disarm();
      Status s = camera->Configure(settings);
      if (s.ok() && !stream) s = camera->Arm();
      if (!s.ok()) {
        LogWarning("live view: " + s.ToString());
        if (camera->state() == DeviceState::kFaulted || !Sleep(1)) break;
        continue;
      }
      configured_version = version;
    }
    const int64_t start_ns = SteadyNowNs();
    Result<Frame> frame = NextFrame(
        *camera, stream, options_.frame_timeout_s + settings.exposure_s * camera->time_scale());
    if (stream && frame.status().code() == StatusCode::kUnimplemented) {
      stream = false;  // trigger full frames instead: arm at the next turn
      configured_version = UINT64_MAX;
      continue;
    }
    if (frame.ok()) {
      Result<cv::Mat> image = FrameImage(*frame);
      if (image.ok())
        Offer(name, *image, "live");
      else
        LogWarning("live view: " + camera->Describe() + ": " + image.status().message());
    } else if (camera->state() == DeviceState::kFaulted) {
      LogWarning("live view stopped for " + camera->Describe() + ": " + frame.status().ToString());
      break;
    } else if (!stream && frame.status().code() == StatusCode::kCorruptData) {
      // A camera that lost a frame refuses the next ones until it is armed again.
      configured_version = UINT64_MAX;
    }
    const double spent_s = SecondsSince(start_ns);
    if (!Sleep(1.0 / options_.fps - spent_s)) break;
  }
  (void)camera->Disarm();
}

void LiveView::Offer(const std::string& camera_name, const cv::Mat& image,
                     const std::string& source) {
  const cv::Mat small = DownscaleForPreview(image, options_.max_width_px);
  Result<std::vector<uint8_t>> jpeg = EncodePreviewJpeg(small, options_.max_width_px);
  if (!jpeg.ok()) {
    LogWarning("live view: " + camera_name + ": " + jpeg.status().message());
    return;
  }
  const ExposureStats stats = MeasureExposure(small);
  const int64_t now_ns = SteadyNowNs();
  nlohmann::json event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    LivePreview& preview = latest_[camera_name];
    const auto last = last_offer_ns_.find(camera_name);
    if (last != last_offer_ns_.end() && now_ns > last->second) {
      const double instant = 1e9 / static_cast<double>(now_ns - last->second);
      preview.fps = preview.fps > 0 ? 0.7 * preview.fps + 0.3 * instant : instant;
    }
    last_offer_ns_[camera_name] = now_ns;
    ++preview.seq;
    preview.jpeg = std::move(*jpeg);
    preview.stats = stats;
    preview.source = source;
  }
  events_.Publish("preview", PreviewJson(camera_name));
}

std::optional<LivePreview> LiveView::Latest(const std::string& camera_name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = latest_.find(camera_name);
  if (it == latest_.end()) return std::nullopt;
  return it->second;
}

nlohmann::json LiveView::PreviewJson(const std::string& camera_name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = latest_.find(camera_name);
  if (it == latest_.end()) return nullptr;
  const LivePreview& p = it->second;
  return {{"camera", camera_name},
          {"seq", p.seq},
          {"fps", p.fps},
          {"source", p.source},
          {"clipped_fraction", p.stats.clipped_fraction},
          {"dark_fraction", p.stats.dark_fraction},
          {"histogram", p.stats.histogram}};
}

}  // namespace hairrig
