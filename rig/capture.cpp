#include "rig/capture.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <thread>

#include "core/contact_sheet.h"
#include "core/file_util.h"
#include "core/image_file.h"
#include "core/log.h"
#include "drivers/camera_support.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture_control.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"

namespace hairrig {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

nlohmann::json CaptureSummary::ToJson() const {
  return {{"dir", dir},
          {"status", status},
          {"message", message},
          {"views_planned", views_planned},
          {"views_completed", views_completed},
          {"views_kept", views_kept},
          {"frames", frames},
          {"bytes", bytes},
          {"faults", faults},
          {"missing_views", missing_views},
          {"setup_s", setup_s},
          {"wall_s", wall_s},
          {"lower_bound_s", lower_bound_s},
          {"efficiency", efficiency}};
}

namespace {

void SleepS(double seconds) {
  if (seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}
std::chrono::milliseconds Ms(double seconds) {
  return std::chrono::milliseconds(
      std::max<int64_t>(1, static_cast<int64_t>(std::ceil(seconds * 1000))));
}
std::string DegText(double deg) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f deg", deg);
  return text;
}

// One camera's shot of one view, waiting for its frame.
struct Shot {
  int view = 0;
  int stop = 0;
  int64_t trigger_ns = 0;
  Clock::time_point deadline;
  double angle_commanded_deg = 0;
  double angle_measured_deg = 0;
};

struct CameraSlot {
  Camera* camera = nullptr;
  std::deque<Shot> queue;
  bool busy = false;  // the collector is working on a shot
  bool needs_reopen =
      false;  // dropped off the bus, or its frames can no longer be paired with triggers
  int gave_up_in_pass = 0;  // reopening failed every attempt in this pass: skip it until the next
  std::thread collector;
};

class Sequencer {
 public:
  Sequencer(Rig& rig, const CapturePlan& plan, const CapturePolicies& policies,
            CaptureDataset& dataset, const CaptureOptions& options)
      : rig_(rig), plan_(plan), policies_(policies), dataset_(dataset), options_(options) {}

  ~Sequencer() { StopCollectors(); }

  // Shoots the views still missing, unless the session already stopped;
  // tells the frame sink the capture finished.
  void Run();
  // The session so far (status from how it ended, or would end now).
  CaptureSummary Summary();
  // Journals session_end and writes the manifest with `summary`'s status; a
  // storage failure of either stops the session (`summary` says so; --resume
  // writes both again).
  void EndSession(CaptureSummary* summary);
  // Stops the run for a storage failure (a write's IoError, a file refused by
  // storage.min_free_mb): journals it, and the summary says to free space,
  // then --resume. The first such failure only.
  void StopForStorage(const Status& status, const Device* device = nullptr, int view = -1);
  bool Stopping() const { return stop_run_.load() || estop_.load(); }
  // A storage failure stopped the session: nothing more is written.
  bool StorageFailed() const { return storage_failed_.load(); }
  // CaptureFolder::write for the capture observers: the dataset's WriteFile.
  // Its first storage failure stops the run at the next stop (from the
  // sequencer's thread: the writer runs on the simulated cameras' threads).
  FileWriter ObserverWriter();

 private:
  // --- setup and teardown --------------------------------------------------
  Status Setup();
  void StopCollectors();
  void OnSafetyInput(const InputLine& line, bool active);
  void OnControl(CaptureControl::Kind kind, const std::string& reason);
  void SafetyStop(const std::string& what, const std::string& input_name, const Device* device,
                  const Status& fault);

  // --- the sweep -------------------------------------------------------------
  void RunPass(const std::vector<int>& views, int pass);
  bool ShootStop(const PlannedStop& stop, const std::vector<int>& views);
  Status Move(double angle_deg, double* measured_deg);
  Status SetLights(const std::map<std::string, double>& levels);
  void PulseTriggerLine(const std::string& line_name, int64_t sent_ns);
  void AllLightsOff();
  Status EnsureCameraReady(CameraSlot& slot);
  Status PrepareCamera(Camera& camera);
  void WaitCollectorsIdle();

  // --- collection --------------------------------------------------------------
  void CollectorLoop(CameraSlot& slot);
  bool Collect(CameraSlot& slot, const Shot& shot);

  // --- bookkeeping -------------------------------------------------------------
  void RecordFault(const Device* device, const Status& status, const std::string& action,
                   int view = -1);
  void StopRun(const std::string& why);
  Status ObserverFailure();
  std::vector<int> MissingViews() const;
  void Progress(const std::string& step, int stop);
  void PlanEta(const std::map<int, std::vector<int>>& views_by_stop);
  void CountStopDone(int stop);
  double EtaLocked(int views_left) const;
  double PlannedBoundLeftLocked() const;
  double ExpectedFrameWallS(const Camera& camera) const;

  Rig& rig_;
  const CapturePlan& plan_;
  const CapturePolicies& policies_;
  CaptureDataset& dataset_;
  const CaptureOptions& options_;

  std::map<std::string, CameraSlot> slots_;  // by serial
  std::mutex mutex_;
  std::condition_variable cv_;
  bool shutdown_ = false;

  std::atomic<bool> stop_run_{false};
  std::atomic<bool> estop_{false};
  std::atomic<bool> storage_failed_{false};  // nothing more is written
  std::string stop_reason_;                  // guarded by mutex_
  std::mutex observer_mutex_;
  Status observer_failure_;  // guarded by observer_mutex_: the observers' first storage failure
  int views_kept_ = 0;       // verified before this session
  double setup_s_ = 0;
  std::atomic<int> faults_{0};
  std::atomic<int> frames_{0};
  std::atomic<uint64_t> bytes_{0};
  Clock::time_point sweep_start_{}, last_frame_{};
  double lower_bound_s_ = 0;
  double last_download_s_ = 0;
  std::atomic<int> stops_done_{0}, stops_total_{0};
  std::atomic<int> sweep_stop_{0};  // the stop the turntable is at or moving to
  int pass_ = 0;
  std::mutex progress_mutex_;
  // The ETA, guarded by progress_mutex_: the lower bound of each stop this
  // pass has still to shoot, and of the stops done since the sweep began.
  std::map<int, double> bound_left_s_;
  std::string last_fault_;  // guarded by progress_mutex_
  double bound_done_s_ = 0;
};

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

// The run stops before the fault is journalled, so that no position_reached
// record follows it (ShootStop journals those under mutex_ unless stopping).
void Sequencer::StopForStorage(const Status& status, const Device* device, int view) {
  if (storage_failed_.exchange(true)) return;
  StopRun("storage: " + status.ToString() +
          ". The frames stored so far are kept; free space on the disk of " + dataset_.dir() +
          ", then continue with --resume");
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

Status Sequencer::Setup() {
  if (!rig_.devices.turntable) return FailedPrecondition("the rig config has no turntable");
  for (Device* d : rig_.devices.All()) {
    Status s;
    for (int attempt = 1; attempt <= policies_.camera.attempts; ++attempt) {
      SleepS(policies_.camera.BackoffBefore(attempt));
      s = d->Open();
      if (s.ok()) break;
    }
    if (!s.ok()) return s.WithContext("opening the rig's devices");
  }
  for (const auto& line : rig_.devices.input_lines) {
    InputLine* l = line.get();
    l->OnChange([this, l](bool active) { OnSafetyInput(*l, active); });
    auto active = l->IsActive();
    if (!active.ok()) return active.status();
    if (*active) {
      return FailedPrecondition(
          l->Describe() + " is active (e-stop pressed or door open): release it, then start again");
    }
  }
  AllLightsOff();
  if (plan_.home_first) {
    HR_RETURN_IF_ERROR(rig_.devices.turntable->Home(Ms(policies_.move_timeout_s)));
  }
  for (const auto& c : rig_.devices.cameras) {
    HR_RETURN_IF_ERROR(PrepareCamera(*c));
    CameraSlot& slot = slots_[c->info().serial];
    slot.camera = c.get();
  }
  for (auto& [serial, slot] : slots_) {
    CameraSlot* s = &slot;
    slot.collector = std::thread([this, s] { CollectorLoop(*s); });
  }
  return Status::Ok();
}

// Opens the camera if it is closed or faulted, then configures and arms it; the
// trigger source follows the config's trigger_line.
Status Sequencer::PrepareCamera(Camera& camera) {
  if (camera.state() == DeviceState::kClosed || camera.state() == DeviceState::kFaulted) {
    (void)camera.Close();
    HR_RETURN_IF_ERROR(camera.Open());
  }
  (void)camera.Disarm();
  CaptureSettings settings = plan_.camera_settings;
  const auto line = rig_.camera_trigger_lines.find(camera.info().name);
  if (line != rig_.camera_trigger_lines.end() && !line->second.empty()) {
    settings.trigger = TriggerSource::kLine;
    settings.trigger_line = line->second;
  } else {
    settings.trigger = TriggerSource::kSoftware;
  }
  HR_RETURN_IF_ERROR(camera.Configure(settings));
  return camera.Arm();
}

void Sequencer::StopCollectors() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
    cv_.notify_all();
  }
  for (auto& [serial, slot] : slots_) {
    if (slot.collector.joinable()) slot.collector.join();
  }
}

void Sequencer::OnSafetyInput(const InputLine& line, bool active) {
  if (!active) return;
  const bool unreadable = line.state() == DeviceState::kFaulted;
  SafetyStop(DescribeSafetyStop(line), line.info().name, &line,
             Unavailable(unreadable ? "safety input unreadable" : "safety input active"));
}

void Sequencer::OnControl(CaptureControl::Kind kind, const std::string& reason) {
  if (kind == CaptureControl::Kind::kEmergency) {
    SafetyStop("software e-stop (" + reason + ")", "software", nullptr,
               Unavailable("software e-stop: " + reason));
    return;
  }
  StopRun("stopped by the operator (" + reason +
          "). The frames stored so far are kept; continue with --resume");
  RecordFault(nullptr, Unavailable("stop requested: " + reason), "end the run after this stop");
}

// Motion stops and the lights go off at once, then the run ends.
void Sequencer::SafetyStop(const std::string& what, const std::string& input_name,
                           const Device* device, const Status& fault) {
  estop_ = true;
  (void)rig_.devices.turntable->Stop();
  AllLightsOff();
  StopRun(what +
          ": motion stopped and lights off. "
          "Release it, check the rig, then continue with --resume");
  RecordFault(device, fault, "stop motion, lights off, end the run");
  // What the devices report right after, for the record (and the tests).
  nlohmann::json lights_on = nlohmann::json::array();
  for (const auto& l : rig_.devices.lights) {
    auto on = l->IsOn();
    if (!on.ok() || *on) lights_on.push_back(l->info().name);
  }
  auto table = rig_.devices.turntable->ReadStatus();
  (void)dataset_.Append({{"event", "safety_stop"},
                         {"input", input_name},
                         {"lights_on", lights_on},
                         {"turntable_moving", table.ok() && table->moving && !table->in_position},
                         {"turntable_deg", table.ok() ? table->position_deg : std::nan("")}});
}

void Sequencer::AllLightsOff() {
  for (const auto& l : rig_.devices.lights) {
    if (l->state() == DeviceState::kReady) (void)l->SetOn(false);
  }
}

Status Sequencer::SetLights(const std::map<std::string, double>& levels) {
  for (const auto& l : rig_.devices.lights) {
    const auto it = levels.find(l->info().name);
    const double level = it == levels.end() ? 0.0 : it->second;
    Status s;
    for (int attempt = 1; attempt <= policies_.light.attempts; ++attempt) {
      SleepS(policies_.light.BackoffBefore(attempt));
      if (l->state() == DeviceState::kFaulted) (void)l->Open();
      s = l->capabilities().dimmable ? l->SetLevel(level) : l->SetOn(level > 0);
      if (s.ok()) break;
      RecordFault(l.get(), s, attempt < policies_.light.attempts ? "retry" : "give up");
    }
    HR_RETURN_IF_ERROR(s);
  }
  return Status::Ok();
}

// Every armed camera on the line hears of the pulse before it is sent, so
// that each frame is paired with its own trigger however late it arrives
// (cameras not shooting at this stop expose too, and their frames are
// discarded as stale later). A pulse that fails may or may not have reached
// the cameras: they are reopened, which clears the pairing, and the views of
// this stop are shot again.
void Sequencer::PulseTriggerLine(const std::string& line_name, int64_t sent_ns) {
  std::vector<CameraSlot*> on_line;
  for (auto& [serial, slot] : slots_) {
    const auto line = rig_.camera_trigger_lines.find(slot.camera->info().name);
    if (line == rig_.camera_trigger_lines.end() || line->second != line_name) continue;
    if (slot.camera->state() == DeviceState::kBusy) slot.camera->LineTriggerSent(sent_ns);
    on_line.push_back(&slot);
  }
  for (const auto& l : rig_.devices.trigger_lines) {
    if (l->info().name != line_name) continue;
    const Status s = l->Pulse(plan_.trigger_pulse);
    if (s.ok()) continue;
    RecordFault(l.get(), s, "reopen the cameras on it, re-shoot later");
    std::lock_guard<std::mutex> lock(mutex_);
    for (CameraSlot* slot : on_line) slot->needs_reopen = true;
  }
}

Status Sequencer::Move(double angle_deg, double* measured_deg) {
  Turntable& table = *rig_.devices.turntable;
  HR_ASSIGN_OR_RETURN(TurntableStatus now, table.ReadStatus());
  if (std::abs(now.position_deg - angle_deg) < table.capabilities().resolution_deg &&
      now.in_position) {
    *measured_deg = now.position_deg;
    return Status::Ok();
  }
  const double expected_s =
      (MoveDurationS(angle_deg - now.position_deg, plan_.motion) + table.capabilities().settle_s) *
      table.time_scale();
  Status s;
  for (int attempt = 1; attempt <= policies_.turntable.attempts && !Stopping(); ++attempt) {
    SleepS(policies_.turntable.BackoffBefore(attempt));
    s = table.MoveTo(angle_deg, plan_.motion, Ms(expected_s + policies_.move_timeout_s));
    if (s.ok() || s.code() != StatusCode::kTimeout) break;
    const bool last = attempt == policies_.turntable.attempts;
    RecordFault(&table, s, last ? "stop the run" : "stop the table and command the move again");
    (void)table.Stop();
  }
  if (Stopping() && s.ok()) return Unavailable("the run was stopped");
  HR_RETURN_IF_ERROR(s);
  HR_ASSIGN_OR_RETURN(TurntableStatus reached, table.ReadStatus());
  *measured_deg = reached.position_deg;
  return Status::Ok();
}

Status Sequencer::EnsureCameraReady(CameraSlot& slot) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!slot.needs_reopen) return Status::Ok();
    if (slot.gave_up_in_pass == pass_)
      return Unavailable(slot.camera->Describe() + ": skipped for the rest of this pass");
    // The collector must be idle before the camera is touched from this thread.
    cv_.wait(lock, [&] { return (slot.queue.empty() && !slot.busy) || shutdown_; });
  }
  Status s;
  for (int attempt = 1; attempt <= policies_.camera.attempts; ++attempt) {
    SleepS(policies_.camera.BackoffBefore(attempt));
    s = PrepareCamera(*slot.camera);
    if (s.ok()) break;
    RecordFault(slot.camera, s,
                attempt < policies_.camera.attempts ? "reopen again after back-off"
                                                    : "skip its views until the next pass");
  }
  if (!s.ok()) slot.gave_up_in_pass = pass_;
  if (s.ok()) {
    (void)dataset_.Append({{"event", "device_reopened"},
                           {"device", slot.camera->info().name},
                           {"serial", slot.camera->info().serial}});
    std::lock_guard<std::mutex> lock(mutex_);
    slot.needs_reopen = false;
  }
  return s;
}

// Shoots the views of one stop; false when the run must end.
bool Sequencer::ShootStop(const PlannedStop& stop, const std::vector<int>& views) {
  if (Stopping()) return false;
  Status space = ObserverFailure();
  if (space.ok()) space = dataset_.CheckFreeSpace(0);
  if (!space.ok()) {
    StopForStorage(space, nullptr);
    return false;
  }
  std::vector<CameraSlot*> shooting;
  std::vector<int> shot_views;
  for (int v : views) {
    CameraSlot& slot = slots_.at(plan_.views[static_cast<size_t>(v)].camera_serial);
    if (EnsureCameraReady(slot).ok()) {
      shooting.push_back(&slot);
      shot_views.push_back(v);
    }
  }
  if (shooting.empty()) return !Stopping();
  sweep_stop_ = stop.index;
  Progress("moving to " + DegText(stop.angle_deg), stop.index);
  double measured = 0;
  const auto before = rig_.devices.turntable->ReadStatus();
  const double from = before.ok() ? before->position_deg : stop.angle_deg;
  {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    if (sweep_start_ == Clock::time_point{}) sweep_start_ = Clock::now();
  }
  const Status moved = Move(stop.angle_deg, &measured);
  if (!moved.ok()) {
    if (!Stopping()) {
      RecordFault(rig_.devices.turntable.get(), moved, "stop the run");
      StopRun(
          moved.ToString() +
          ". The frames stored so far are kept; check the turntable, then continue with --resume");
    }
    return false;
  }
  lower_bound_s_ += StopLowerBoundS(plan_, rig_.devices, from, stop);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (Stopping()) return false;
    (void)dataset_.Append({{"event", "position_reached"},
                           {"stop", stop.index},
                           {"commanded_deg", stop.angle_deg},
                           {"measured_deg", measured}});
  }
  if (const Status s = SetLights(stop.light_levels); !s.ok()) {
    StopRun(s.ToString() + ": cannot light the views; check the panel's power and connection");
    return false;
  }
  if (Stopping()) return false;
  Progress("exposing", stop.index);
  // One pulse per trigger line used by this stop; a software trigger for the rest.
  std::set<std::string> lines;
  for (CameraSlot* slot : shooting) {
    const auto it = rig_.camera_trigger_lines.find(slot->camera->info().name);
    if (it != rig_.camera_trigger_lines.end() && !it->second.empty()) lines.insert(it->second);
  }
  const int64_t trigger_ns = SteadyNowNs();
  const Clock::time_point trigger_time = Clock::now();
  for (const std::string& name : lines) PulseTriggerLine(name, trigger_ns);
  double exposure_wall_s = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (size_t i = 0; i < shooting.size(); ++i) {
      Camera& camera = *shooting[i]->camera;
      const auto line = rig_.camera_trigger_lines.find(camera.info().name);
      if (line == rig_.camera_trigger_lines.end() || line->second.empty()) {
        if (const Status s = camera.SoftwareTrigger(); !s.ok()) shooting[i]->needs_reopen = true;
      }
      Shot shot{shot_views[i], stop.index, trigger_ns, {}, stop.angle_deg, measured};
      shot.deadline =
          trigger_time + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                             ExpectedFrameWallS(camera) + policies_.frame_timeout_s));
      shooting[i]->queue.push_back(shot);
      exposure_wall_s =
          std::max(exposure_wall_s, plan_.camera_settings.exposure_s * camera.time_scale());
      const CameraCapabilities caps = camera.capabilities();
      last_download_s_ =
          std::max(last_download_s_, (caps.readout_s + caps.download_s) * camera.time_scale());
    }
    cv_.notify_all();
  }
  // The turntable may move once every exposure has ended.
  std::this_thread::sleep_until(trigger_time + std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(exposure_wall_s)));
  return !Stopping();
}

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

void Sequencer::WaitCollectorsIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] {
    for (auto& [serial, slot] : slots_) {
      if (!slot.queue.empty() || slot.busy) return false;
    }
    return true;
  });
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

void Sequencer::RunPass(const std::vector<int>& views, int pass) {
  pass_ = pass;
  std::map<int, std::vector<int>> by_stop;
  for (int v : views) by_stop[plan_.views[static_cast<size_t>(v)].stop].push_back(v);
  stops_total_ = stops_done_.load() + static_cast<int>(by_stop.size());
  PlanEta(by_stop);
  if (pass > 1) {
    (void)dataset_.Append({{"event", "reshoot_pass"}, {"pass", pass}, {"views", views}});
    Progress("re-shooting " + std::to_string(views.size()) + " views", by_stop.begin()->first);
  }
  for (const auto& [stop, stop_views] : by_stop) {
    if (!ShootStop(plan_.stops[static_cast<size_t>(stop)], stop_views)) break;
    CountStopDone(stop);
  }
  Progress("waiting for the last frames", static_cast<int>(plan_.stops.size()) - 1);
  WaitCollectorsIdle();
}

void Sequencer::Run() {
  views_kept_ = dataset_.VerifiedFrameCount();
  const auto t0 = Clock::now();
  if (options_.control) {
    options_.control->Attach(
        [this](CaptureControl::Kind kind, const std::string& why) { OnControl(kind, why); });
  }
  // A session that stopped before it began (its start not journalled) opens no device.
  Status setup = Stopping() ? Status::Ok() : Setup();
  setup_s_ = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!setup.ok()) {
    RecordFault(nullptr, setup, "stop the run");
    StopRun(setup.ToString());
  }
  for (int pass = 1; pass <= policies_.camera.attempts && !Stopping(); ++pass) {
    const std::vector<int> missing = MissingViews();
    if (missing.empty()) break;
    if (pass > 1) SleepS(policies_.camera.BackoffBefore(pass));
    RunPass(missing, pass);
  }
  WaitCollectorsIdle();
  StopCollectors();
  AllLightsOff();
  for (const auto& c : rig_.devices.cameras) (void)c->Disarm();
  for (const auto& l : rig_.devices.input_lines) l->OnChange(nullptr);
  if (options_.control) options_.control->Detach();
  if (options_.sink) options_.sink->OnCaptureFinished();
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

// <capture>/contact_sheet.png from the verified frames, in plan order, unless
// it would leave less than storage.min_free_mb free (IoError, as a failed write).
Status WriteContactSheet(CaptureDataset& dataset, const CapturePlan& plan) {
  std::vector<cv::Mat> thumbs;
  std::vector<std::string> labels;
  for (const FrameRecord& r : dataset.VerifiedFrames()) {
    Result<cv::Mat> image = ReadImageFile(dataset.dir() + "/" + r.file, cv::IMREAD_REDUCED_COLOR_4);
    if (!image.ok()) continue;
    thumbs.push_back(std::move(image).value());
    labels.push_back(std::filesystem::path(r.file).filename().string());
  }
  if (thumbs.empty()) return Status::Ok();
  const int columns = std::max<int>(
      1, static_cast<int>(plan.views.size() / std::max<size_t>(1, plan.stops.size())) * 4);
  const cv::Mat sheet = MakeContactSheet(thumbs, labels, columns, 240);
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", sheet, png)) return Internal("contact sheet: PNG encoding failed");
  return dataset.WriteFile(dataset.dir() + "/contact_sheet.png", png.data(), png.size());
}

std::string ReadText(const std::string& path) {
  auto bytes = ReadFileBytes(path);
  return bytes.ok() ? std::string(bytes->begin(), bytes->end()) : std::string();
}

// The plan as the journal's view_planned records.
std::vector<PlannedViewRecord> PlannedViewRecords(const CapturePlan& plan) {
  std::vector<PlannedViewRecord> records;
  for (const PlannedView& v : plan.views) {
    const PlannedStop& stop = plan.stops[static_cast<size_t>(v.stop)];
    records.push_back(
        {v.index, v.stop, stop.angle_deg, v.camera_name, v.camera_serial, stop.light_levels});
  }
  return records;
}

// The config of this session: the rig config, or a resumed capture's
// snapshot (*config_text is left empty then). A rig built without its
// extensions (a replay) ignores the config sections they would read.
Result<RigConfig> LoadSessionConfig(const CaptureOptions& options, std::string* config_text) {
  const UnclaimedSections unclaimed =
      options.rig_build.attach_extensions ? UnclaimedSections::kRefuse : UnclaimedSections::kIgnore;
  if (options.resume) {
    HR_ASSIGN_OR_RETURN(const CaptureMetadata metadata, ReadResumableCapture(options.out_dir));
    const fs::path snapshot = fs::absolute(options.out_dir).lexically_normal() / "rig.yaml";
    return LoadRigConfig(snapshot.string(), metadata.config_dir, unclaimed);
  }
  if (fs::exists(options.out_dir)) {
    return FailedPrecondition(
        options.out_dir +
        " already exists: choose a new --out folder, or add --resume to continue it");
  }
  if (options.rig) {  // the rig's own config, as it was loaded
    *config_text = ReadText(options.rig->config.path);
    return options.rig->config;
  }
  HR_ASSIGN_OR_RETURN(RigConfig config,
                      LoadRigConfig(options.config_path, options.config_relative_to, unclaimed));
  *config_text = ReadText(options.config_path);
  return config;
}

// Room on the capture's disk for the views left to shoot: all of them, or
// those of a resumed capture (`resumed`) without a verified frame.
Status CheckSpaceToFinish(const CaptureStorage& storage, const std::string& out_dir,
                          const CapturePlan& plan, const DeviceSet& devices,
                          const CapturePolicies& policies, const CaptureDataset* resumed) {
  std::vector<int> left;
  for (const PlannedView& v : plan.views) {
    if (!resumed || !resumed->HasVerifiedFrame(v.index)) left.push_back(v.index);
  }
  // The file system the capture lands on: the nearest folder that exists.
  fs::path probe = fs::absolute(out_dir);
  while (!fs::exists(probe) && probe.has_parent_path() && probe != probe.parent_path())
    probe = probe.parent_path();
  HR_ASSIGN_OR_RETURN(const uint64_t free, storage.FreeBytes(probe.string()));
  const uint64_t needed = BytesNeededToFinish(plan, devices, left, policies);
  if (free >= needed) return Status::Ok();
  return IoError(
      probe.string() + ": " + std::to_string(free / 1000000) + " MB free, the " +
      std::to_string(left.size()) + " views left to shoot need up to " +
      std::to_string(needed / 1000000) + " MB (their frames plus storage.min_free_mb): " +
      (resumed ? "free space, then run --resume again" : "free space or choose another --out"));
}

// Journals the session's start (and a new capture's plan) and writes the
// manifest; the first error.
Status StartSession(CaptureDataset& dataset, const CaptureOptions& options,
                    const std::string& subject, const RigConfig& config, const CapturePlan& plan,
                    const std::vector<PlannedViewRecord>& planned_views,
                    const ResumeReport& report) {
  HR_RETURN_IF_ERROR(dataset.Append({{"event", "session_start"},
                                     {"resume", options.resume},
                                     {"subject", subject},
                                     {"rig", config.name},
                                     {"config_dir", config.relative_to},
                                     {"views_planned", plan.views.size()},
                                     {"frames_verified", report.frames_verified},
                                     {"quarantined", report.quarantined},
                                     {"partial_removed", report.partial_removed.size()}}));
  if (!options.resume) HR_RETURN_IF_ERROR(dataset.JournalPlan(planned_views));
  return dataset.WriteManifest("in_progress");
}

// A storage failure (IoError) stops the session (Sequencer::StopForStorage)
// and is Ok here; any other error is returned.
Status StopIfStorage(Sequencer& sequencer, const Status& status) {
  if (status.code() != StatusCode::kIoError) return status;
  sequencer.StopForStorage(status);
  return Status::Ok();
}

}  // namespace

std::shared_ptr<CaptureStorage> CaptureStorageFor(const CaptureOptions& options, const Rig* rig) {
  if (options.storage) return options.storage;
  if (rig && rig->capture_storage) return rig->capture_storage;
  return DefaultCaptureStorage();
}

Status CaptureOptions::Check() const {
  if (out_dir.empty())
    return InvalidArgument("--out is required: the folder the capture is written to");
  return rig_build.Check().WithContext("rig_build");
}

Result<CaptureSummary> RunCapture(const CaptureOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  std::string config_text;
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadSessionConfig(options, &config_text));
  std::unique_ptr<Rig> built;
  if (!options.rig) {
    HR_ASSIGN_OR_RETURN(built, BuildRig(config, options.rig_build));
  }
  Rig* const rig = options.rig ? options.rig : built.get();
  HR_ASSIGN_OR_RETURN(CapturePlan plan, ReadCapturePlan(config.root, rig->devices));
  HR_ASSIGN_OR_RETURN(CapturePolicies policies, ReadCapturePolicies(config.root));
  HR_RETURN_IF_ERROR(CheckCalibrationSection(config));
  const std::shared_ptr<CaptureStorage> storage = CaptureStorageFor(options, rig);
  DatasetOptions dataset_options;
  dataset_options.png_compression = policies.png_compression;
  dataset_options.min_free_bytes = policies.MinFreeBytes();
  const std::vector<PlannedViewRecord> planned_views = PlannedViewRecords(plan);
  std::unique_ptr<CaptureDataset> dataset;
  ResumeReport report;
  if (options.resume) {
    HR_ASSIGN_OR_RETURN(
        dataset, CaptureDataset::OpenForResume(options.out_dir, dataset_options, &report, storage));
    // A resumed capture's plan is checked before anything else is written.
    HR_RETURN_IF_ERROR(dataset->JournalPlan(planned_views));
  }
  HR_RETURN_IF_ERROR(
      CheckSpaceToFinish(*storage, options.out_dir, plan, rig->devices, policies, dataset.get()));
  if (!options.resume) {
    CaptureMetadata metadata;
    metadata.config_source = fs::absolute(config.path).lexically_normal().string();
    metadata.config_dir = config.relative_to;
    metadata.subject = options.subject;
    HR_ASSIGN_OR_RETURN(dataset, CaptureDataset::Create(options.out_dir, config_text, metadata,
                                                        dataset_options, storage));
  }
  const std::string subject = options.resume ? dataset->metadata().subject : options.subject;
  dataset->SetPlanSummary(static_cast<int>(plan.views.size()), subject, config.name);
  Sequencer sequencer(*rig, plan, policies, *dataset, options);
  // From here on a storage failure stops the session, resumable, and the call returns a summary.
  HR_RETURN_IF_ERROR(StopIfStorage(
      sequencer, StartSession(*dataset, options, subject, config, plan, planned_views, report)));
  const CaptureFolder folder{dataset->dir(), sequencer.ObserverWriter()};
  Status begun = Status::Ok();
  for (const auto& observer : rig->capture_observers) {
    if (!begun.ok() || sequencer.Stopping()) break;
    begun = StopIfStorage(sequencer, observer->OnCaptureBegin(plan, folder));
  }
  if (begun.ok()) sequencer.Run();
  rig->devices.CloseAll();
  const CaptureSummary shot = sequencer.Summary();
  // Every observer is told, so that none writes through `folder` after this
  // call. A storage failure stops the session; the first other error is returned.
  Status ended = Status::Ok();
  for (const auto& observer : rig->capture_observers) {
    const Status s = StopIfStorage(sequencer, observer->OnCaptureEnd(shot));
    if (ended.ok()) ended = s;
  }
  HR_RETURN_IF_ERROR(begun);
  if (ended.ok() && !sequencer.StorageFailed()) {
    const Status sheet = WriteContactSheet(*dataset, plan);
    if (!StopIfStorage(sequencer, sheet).ok()) LogWarning(sheet.ToString());
  }
  CaptureSummary summary = sequencer.Summary();
  sequencer.EndSession(&summary);
  HR_RETURN_IF_ERROR(ended);
  return summary;
}

}  // namespace hairrig
