// The Sequencer's bookkeeping (rig/capture_sequencer.h): faults and storage
// stops, progress and ETA, the summary and the session's end.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/log.h"
#include "core/status.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/capture_sequencer.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

void Sequencer::RecordFault(const Device* device, const Status& status, const std::string& action,
                            int view) {
  ++faults_;
  nlohmann::json r = {{"event", "fault"}, {"what", status.ToString()}, {"action", action}};
  if (device) {
    r["device"] = device->info().name;
    r["serial"] = device->info().serial;
  }
  if (view >= 0) r["view"] = view;
  LogWarning("fault: " + status.ToString() + " -> " + action);
  {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    last_fault_ = status.ToString() + " -> " + action;
  }
  (void)dataset_.Append(std::move(r));  // a journal failure must not hide the fault itself
}

void Sequencer::StopRun(const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stop_reason_.empty()) stop_reason_ = why;
  stop_run_ = true;
  cv_.notify_all();
}

namespace {

// What the operator does after storage fault `status`: free space when the
// write ran out of it (ENOSPC, EDQUOT) or the capture's disk, as its storage
// reports it, has no room for a few more frames above storage.min_free_mb;
// else mend what the error names (a folder or a read-only file where a file
// is written, permissions).
std::string StorageRemedy(const Status& status, const CaptureDataset& dataset) {
  constexpr uint64_t kFewFramesBytes = uint64_t{64} << 20;
  const std::string& message = status.message();
  const bool out_of_space = message.find(std::strerror(ENOSPC)) != std::string::npos ||
                            message.find(std::strerror(EDQUOT)) != std::string::npos;
  if (out_of_space || !dataset.CheckFreeSpace(kFewFramesBytes).ok())
    return "free space on the disk of " + dataset.dir();
  return "mend what the error names (the disk of " + dataset.dir() + " has room)";
}

}  // namespace

// The run stops before the fault is journalled, so that no position_reached
// record follows it (ShootStop journals those under mutex_ unless stopping).
void Sequencer::StopForStorage(const Status& status, const Device* device, int view) {
  if (storage_failed_.exchange(true)) return;
  StopRun("storage: " + status.ToString() + ". The frames stored so far are kept; " +
          StorageRemedy(status, dataset_) + ", then continue with --resume");
  RecordFault(device, status, "stop the run", view);
}

FileWriter Sequencer::ObserverWriter() {
  return [this](const std::string& path, const void* data, size_t size) {
    const Status s = dataset_.WriteFile(path, data, size);
    if (s.code() == StatusCode::kIoError) {
      std::lock_guard<std::mutex> lock(observer_mutex_);
      if (observer_failure_.ok()) observer_failure_ = s;
    }
    return s;
  };
}

Status Sequencer::ObserverFailure() {
  std::lock_guard<std::mutex> lock(observer_mutex_);
  return observer_failure_;
}

double Sequencer::ExpectedFrameWallS(const Camera& camera) const {
  const CameraCapabilities caps = camera.capabilities();
  return (plan_.camera_settings.exposure_s + caps.readout_s + caps.download_s) *
         camera.time_scale();
}

std::vector<int> Sequencer::MissingViews() const {
  std::vector<int> missing;
  for (const PlannedView& v : plan_.views) {
    if (!dataset_.HasVerifiedFrame(v.index)) missing.push_back(v.index);
  }
  return missing;
}

void Sequencer::Progress(const std::string& step, int stop) {
  if (!options_.on_progress) return;
  std::lock_guard<std::mutex> lock(progress_mutex_);
  CaptureProgress p;
  p.views_done = dataset_.VerifiedFrameCount();
  p.views_total = static_cast<int>(plan_.views.size());
  p.stop = stop;
  p.stops_total = static_cast<int>(plan_.stops.size());
  p.step = step;
  p.faults = faults_.load();
  p.last_fault = last_fault_;
  p.eta_s = EtaLocked(p.views_total - p.views_done);
  options_.on_progress(p);
}

// The longer of the sweep's and the storage's time left: the lower bound of
// the stops left times the sweep's pace so far (wall seconds per second of
// lower bound, at least 1; 1 before the first stop is done), and the views
// left times the wall time per view stored so far (downloads, decoding and
// writing may lag the sweep).
double Sequencer::EtaLocked(int views_left) const {
  if (sweep_start_ == Clock::time_point{}) return PlannedBoundLeftLocked();
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - sweep_start_).count();
  const double pace = bound_done_s_ > 0 ? std::max(1.0, elapsed_s / bound_done_s_) : 1.0;
  const int stored = frames_.load();
  const double storage_s = stored > 0 ? elapsed_s / stored * std::max(0, views_left) : 0.0;
  return std::max(PlannedBoundLeftLocked() * pace, storage_s);
}

double Sequencer::PlannedBoundLeftLocked() const {
  double left = 0;
  for (const auto& [stop, bound] : bound_left_s_) left += bound;
  return left;
}

void Sequencer::PlanEta(const std::map<int, std::vector<int>>& views_by_stop) {
  const auto status = rig_.devices.turntable->ReadStatus();
  double from = status.ok()
                    ? status->position_deg
                    : plan_.stops[static_cast<size_t>(views_by_stop.begin()->first)].angle_deg;
  std::lock_guard<std::mutex> lock(progress_mutex_);
  bound_left_s_.clear();
  for (const auto& [stop, views] : views_by_stop) {
    const PlannedStop& planned = plan_.stops[static_cast<size_t>(stop)];
    bound_left_s_[stop] = StopLowerBoundS(plan_, rig_.devices, from, planned);
    from = planned.angle_deg;
  }
}

void Sequencer::CountStopDone(int stop) {
  ++stops_done_;
  std::lock_guard<std::mutex> lock(progress_mutex_);
  const auto it = bound_left_s_.find(stop);
  if (it == bound_left_s_.end()) return;
  bound_done_s_ += it->second;
  bound_left_s_.erase(it);
}

CaptureSummary Sequencer::Summary() {
  CaptureSummary summary;
  summary.dir = dataset_.dir();
  summary.views_planned = static_cast<int>(plan_.views.size());
  summary.views_kept = views_kept_;
  summary.setup_s = setup_s_;
  summary.missing_views = MissingViews();
  summary.views_completed = summary.views_planned - static_cast<int>(summary.missing_views.size());
  summary.frames = frames_.load();
  summary.bytes = bytes_.load();
  summary.faults = faults_.load();
  if (sweep_start_ != Clock::time_point{} && last_frame_ > sweep_start_) {
    summary.wall_s = std::chrono::duration<double>(last_frame_ - sweep_start_).count();
  }
  summary.lower_bound_s = lower_bound_s_ + (summary.frames > 0 ? last_download_s_ : 0);
  summary.efficiency = summary.wall_s > 0 ? summary.lower_bound_s / summary.wall_s : 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    summary.message = stop_reason_;
  }
  if (stop_run_ || estop_) {
    summary.status = "stopped";
  } else if (!summary.missing_views.empty()) {
    summary.status = "incomplete";
    summary.message =
        std::to_string(summary.missing_views.size()) + " views still missing after " +
        std::to_string(policies_.camera.attempts) +
        " passes (see the faults in journal.jsonl); fix the cause, then run again with --resume";
  } else {
    summary.status = "complete";
  }
  return summary;
}

void Sequencer::EndSession(CaptureSummary* summary) {
  const Status journalled = dataset_.Append({{"event", "session_end"},
                                             {"status", summary->status},
                                             {"message", summary->message},
                                             {"views_completed", summary->views_completed},
                                             {"frames", summary->frames},
                                             {"faults", summary->faults}});
  const Status written = dataset_.WriteManifest(journalled.ok() ? summary->status : "stopped");
  const Status failed = journalled.ok() ? written : journalled;
  if (failed.ok()) return;
  storage_failed_ = true;  // the fault cannot be journalled after session_end
  StopRun("storage: " + failed.ToString() + ". Free space on the disk of " + dataset_.dir() +
          ", then continue with --resume");
  *summary = Summary();
}

}  // namespace hairrig
