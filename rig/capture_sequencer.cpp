#include "rig/capture_sequencer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/status.h"
#include "drivers/camera_support.h"
#include "rig/capture_control.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

namespace detail {

std::chrono::milliseconds Ms(double seconds) {
  return std::chrono::milliseconds(
      std::max<int64_t>(1, static_cast<int64_t>(std::ceil(seconds * 1000))));
}

}  // namespace detail

using detail::Ms;

namespace {

void SleepS(double seconds) {
  if (seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}
std::string DegText(double deg) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f deg", deg);
  return text;
}

}  // namespace

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

void Sequencer::WaitCollectorsIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] {
    for (auto& [serial, slot] : slots_) {
      if (!slot.queue.empty() || slot.busy) return false;
    }
    return true;
  });
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

}  // namespace hairrig
