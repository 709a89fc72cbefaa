// The Sequencer's collectors (rig/capture_sequencer.h): one thread per camera
// waits for each queued shot's frame, drops stale ones and stores it.
#include <algorithm>
#include <chrono>
#include <mutex>
#include <string>

#include "core/status.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/capture_sequencer.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;
using detail::Ms;

void Sequencer::CollectorLoop(CameraSlot& slot) {
  for (;;) {
    Shot shot;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return shutdown_ || !slot.queue.empty(); });
      if (slot.queue.empty()) return;
      shot = slot.queue.front();
      slot.queue.pop_front();
      slot.busy = true;
    }
    Collect(slot, shot);
    std::lock_guard<std::mutex> lock(mutex_);
    slot.busy = false;
    cv_.notify_all();
  }
}

bool Sequencer::Collect(CameraSlot& slot, const Shot& shot) {
  Camera& camera = *slot.camera;
  if (storage_failed_) return false;  // the view stays missing for --resume
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (slot.needs_reopen) {
      RecordFault(&camera, Unavailable("the camera is being reopened"), "re-shoot later",
                  shot.view);
      return false;
    }
  }
  // A camera delivers its frames one after another: when earlier frames are
  // still coming out, this one's transfer starts only now.
  const Clock::time_point deadline = std::max(
      shot.deadline,
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                         ExpectedFrameWallS(camera) + policies_.frame_timeout_s)));
  for (;;) {
    const double left_s = std::chrono::duration<double>(deadline - Clock::now()).count();
    Result<Frame> frame = left_s > 0
                              ? camera.WaitFrame(Ms(left_s))
                              : Result<Frame>(Timeout(camera.Describe() + ": no frame for view " +
                                                      std::to_string(shot.view) + " in time"));
    if (!frame.ok()) {
      if (frame.status().code() != StatusCode::kTimeout) {
        std::lock_guard<std::mutex> lock(mutex_);
        slot.needs_reopen = true;
      }
      RecordFault(&camera, frame.status(),
                  frame.status().code() == StatusCode::kTimeout
                      ? "re-shoot later"
                      : "reopen the camera, re-shoot later",
                  shot.view);
      return false;
    }
    if (frame->trigger_time_ns < shot.trigger_ns) {
      (void)dataset_.Append({{"event", "stale_frame_discarded"},
                             {"serial", camera.info().serial},
                             {"trigger_time_ns", frame->trigger_time_ns},
                             {"waiting_for_view", shot.view}});
      continue;
    }
    const PlannedView& view = plan_.views[static_cast<size_t>(shot.view)];
    const CameraCapabilities caps = camera.capabilities();
    FrameContext context{shot.view,
                         shot.stop,
                         view.camera_name,
                         shot.angle_commanded_deg,
                         shot.angle_measured_deg,
                         caps.width_px,
                         caps.height_px};
    auto stored = dataset_.StoreFrame(*frame, context);
    if (!stored.ok()) {
      if (stored.status().code() == StatusCode::kIoError) {
        StopForStorage(stored.status(), &camera, shot.view);
      } else {
        RecordFault(&camera, stored.status(), "re-shoot later", shot.view);
      }
      return false;
    }
    ++frames_;
    bytes_ += stored->record.bytes;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      last_frame_ = Clock::now();
    }
    Progress("stored view " + std::to_string(shot.view), sweep_stop_.load());
    if (options_.sink) {
      StoredFrame out{shot.view,
                      shot.stop,
                      view.camera_name,
                      camera.info().serial,
                      stored->path,
                      stored->record.sha256,
                      shot.angle_commanded_deg,
                      shot.angle_measured_deg,
                      stored->image};
      options_.sink->OnFrameStored(out);
    }
    return true;
  }
}

}  // namespace hairrig
