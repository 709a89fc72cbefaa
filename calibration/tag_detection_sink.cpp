#include "calibration/tag_detection_sink.h"

#include <atomic>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "core/clock.h"

namespace hairrig {
std::string DetectionKey(const std::string& frame_path) {
  std::error_code ec;
  const auto canonical = std::filesystem::weakly_canonical(frame_path, ec);
  return ec ? frame_path : canonical.string();
}

struct TagDetectionSink::Impl {
  CalibBox box;
  TagDetectorOptions detector;
  std::mutex mutex;
  std::condition_variable work_ready, idle;
  std::deque<StoredFrame> queue;
  int busy = 0;
  bool stopping = false;
  std::map<std::string, ViewObservations> results;
  std::atomic<int64_t> last_frame_ns{0};
  std::atomic<int64_t> last_detected_ns{0};
  std::vector<std::thread> workers;

  void Work() {
    auto tag_detector = TagDetector::Create(detector);
    for (;;) {
      StoredFrame frame;
      {
        std::unique_lock<std::mutex> lock(mutex);
        work_ready.wait(lock, [&] { return stopping || !queue.empty(); });
        if (stopping) return;
        frame = std::move(queue.front());
        queue.pop_front();
        ++busy;
      }
      std::optional<ViewObservations> observations;
      if (tag_detector.ok() && !frame.image.empty()) {
        auto detections = (*tag_detector)->Detect(frame.image);
        if (detections.ok()) observations = MatchToBox(*detections, box);
      }
      const std::string key = DetectionKey(frame.path);
      std::lock_guard<std::mutex> lock(mutex);
      if (observations) results[key] = std::move(*observations);
      last_detected_ns = SteadyNowNs();
      --busy;
      if (busy == 0 && queue.empty()) idle.notify_all();
    }
  }
};

TagDetectionSink::TagDetectionSink(CalibBox box, TagDetectorOptions detector, int threads)
    : impl_(std::make_unique<Impl>()) {
  impl_->box = std::move(box);
  impl_->detector = detector;
  for (int t = 0; t < std::max(1, threads); ++t)
    impl_->workers.emplace_back([this] { impl_->Work(); });
}

TagDetectionSink::~TagDetectionSink() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->work_ready.notify_all();
  for (std::thread& worker : impl_->workers) worker.join();
}

void TagDetectionSink::OnFrameStored(const StoredFrame& frame) {
  impl_->last_frame_ns = SteadyNowNs();
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->queue.push_back(frame);
  }
  impl_->work_ready.notify_one();
}

std::map<std::string, ViewObservations> TagDetectionSink::WaitForAll() {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->idle.wait(lock, [&] { return impl_->queue.empty() && impl_->busy == 0; });
  return impl_->results;
}

int64_t TagDetectionSink::last_frame_ns() const { return impl_->last_frame_ns; }
int64_t TagDetectionSink::last_detected_ns() const { return impl_->last_detected_ns; }

}  // namespace hairrig
