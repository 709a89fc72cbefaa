#include "rig/replay.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

#include "core/config.h"
#include "core/file_util.h"
#include "core/sha256.h"
#include "drivers/always_present_device.h"
#include "drivers/camera_support.h"
#include "drivers/trigger_bus.h"
#include "rig/capture_dataset.h"
#include "rig/journal_records.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

namespace {

// Milliseconds since the epoch of a journal time stamp ("...T10:04:05.123Z").
double UtcSeconds(const std::string& text) {
  std::tm tm{};
  int ms = 0;
  if (std::sscanf(text.c_str(), "%d-%d-%dT%d:%d:%d.%dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                  &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &ms) != 7) {
    return 0;
  }
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<double>(timegm(&tm)) + ms / 1000.0;
}

bool SameAngle(double a, double b) { return std::abs(a - b) < 1e-6; }
}  // namespace

struct RecordedStop {
  double commanded_deg = 0;
  double measured_deg = 0;
  double seconds_since_previous = 0;  // recorded wall time from the previous stop's arrival
};

using LightState = std::map<std::string, double>;  // light name -> level

struct RecordedFrame {
  std::string path;
  std::string sha256;  // checked again when the frame is served
  uint64_t bytes = 0;
  LightState lights;  // the panels when it was shot (from its view_planned record)
  std::string extension;
  double commanded_deg = 0;
  double exposure_s = 0;
  double gain_db = 0;
  double download_s = 0;  // recorded trigger -> received
};

class ReplaySource {
 public:
  ReplayOptions options;
  std::vector<RecordedStop> stops;
  std::multimap<std::string, RecordedFrame> frames;  // by camera serial
  std::map<std::string, std::pair<int, int>> sizes;  // serial -> width, height

  // The turntable's commanded angle now (shared with the cameras).
  void SetTarget(double deg) {
    std::lock_guard<std::mutex> lock(mutex_);
    target_deg_ = deg;
  }
  double Target() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return target_deg_;
  }
  void SetLight(const std::string& name, double level) {
    std::lock_guard<std::mutex> lock(mutex_);
    lights_[name] = level;
  }
  LightState Lights() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return lights_;
  }
  const RecordedStop* FindStop(double commanded_deg) const {
    for (const RecordedStop& s : stops) {
      if (SameAngle(s.commanded_deg, commanded_deg)) return &s;
    }
    return nullptr;
  }
  // The frame of `serial` shot at that angle under that light state (a plan may
  // shoot one angle under several light states).
  const RecordedFrame* FindFrame(const std::string& serial, double commanded_deg,
                                 const LightState& lights) const {
    const auto range = frames.equal_range(serial);
    for (auto it = range.first; it != range.second; ++it) {
      if (SameAngle(it->second.commanded_deg, commanded_deg) &&
          SameLights(it->second.lights, lights))
        return &it->second;
    }
    return nullptr;
  }
  double Scaled(double recorded_s) const {
    return options.speed > 0 ? recorded_s / options.speed : 0;
  }

  TriggerBus triggers;  // cameras armed for a line listen here

 private:
  static bool SameLights(const LightState& recorded, const LightState& now) {
    for (const auto& [name, level] : recorded) {
      const auto it = now.find(name);
      if (std::abs((it == now.end() ? 0.0 : it->second) - level) > 1e-6) return false;
    }
    return true;
  }

  mutable std::mutex mutex_;
  double target_deg_ = 0;
  LightState lights_;
};

namespace {

// The recorded stops: each commanded angle once, with its measured angle and
// the wall time from the previous arrival in the same session.
Status AddStops(const std::string& journal_path, const std::vector<nlohmann::json>& records,
                ReplaySource* source) {
  double previous_arrival = 0;
  for (size_t i = 0; i < records.size(); ++i) {
    const std::string event = JournalEvent(records[i]);
    if (event == "session_start") previous_arrival = 0;
    if (event != "position_reached") continue;
    HR_ASSIGN_OR_RETURN(const PositionRecord p,
                        PositionRecord::FromJson(records[i], JournalLine(journal_path, i)));
    const double t = UtcSeconds(p.time_utc);
    const RecordedStop stop{p.commanded_deg, p.measured_deg,
                            previous_arrival > 0 ? t - previous_arrival : 0};
    previous_arrival = t;
    if (!source->FindStop(stop.commanded_deg)) source->stops.push_back(stop);
  }
  return Status::Ok();
}

// Recorded trigger-to-arrival time, within [0, 60] s: a journal's time stamps
// cannot make a replayed camera wait longer than that.
double DownloadSeconds(const FrameRecord& r) {
  const double s =
      1e-9 * (static_cast<double>(r.received_time_ns) - static_cast<double>(r.trigger_time_ns));
  return std::clamp(s, 0.0, 60.0);
}

}  // namespace

Status ReplayOptions::Check() const {
  if (!(speed >= 0) || !std::isfinite(speed))
    return InvalidArgument("replay speed must be 0 (as fast as possible) or a positive factor");
  return Status::Ok();
}

Result<std::shared_ptr<ReplaySource>> OpenReplaySource(const std::string& capture_dir,
                                                       const ReplayOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  // Read-only: the recorded folder is never modified (OpenForResume would repair it).
  const std::string journal_path = capture_dir + "/journal.jsonl";
  HR_ASSIGN_OR_RETURN(const std::vector<nlohmann::json> records, ReadJournalRecords(journal_path));
  HR_ASSIGN_OR_RETURN(const auto planned, PlannedViews(journal_path, records));
  HR_ASSIGN_OR_RETURN(const auto verified, VerifiedFrames(capture_dir, records));
  auto source = std::make_shared<ReplaySource>();
  source->options = options;
  HR_RETURN_IF_ERROR(AddStops(journal_path, records, source.get()));
  for (const auto& [view, r] : verified) {
    const RecordedFrame f{
        capture_dir + "/" + r.file,
        r.sha256,
        r.bytes,
        planned.at(view).lights,  // VerifiedFrames checked that the view is planned
        FileExtension(r.file),
        r.angle_commanded_deg,
        r.exposure_s,
        r.gain_db,
        DownloadSeconds(r)};
    source->frames.emplace(r.serial, f);
    source->sizes[r.serial] = {r.width_px, r.height_px};
  }
  if (source->frames.empty())
    return NotFound(capture_dir + ": the capture has no verified frames to replay");
  return source;
}

Status CheckReplayOutDir(const std::string& recorded_dir, const std::string& out_dir) {
  // A file inside out_dir resolves inside the recording exactly when out_dir is the recording or
  // lies inside it.
  if (ResolveInside(out_dir + "/x", recorded_dir).ok()) {
    return InvalidArgument("--out " + out_dir + " lies inside the recording " + recorded_dir +
                           ", which replay never writes into: choose a folder outside it");
  }
  return Status::Ok();
}

int ReplayFrameCount(const ReplaySource& source) { return static_cast<int>(source.frames.size()); }

namespace {

template <typename Base>
class ReplayDevice : public AlwaysPresentDevice<Base> {
 public:
  ReplayDevice(DeviceInfo info, std::shared_ptr<ReplaySource> source)
      : AlwaysPresentDevice<Base>(std::move(info)), source_(std::move(source)) {}

 protected:
  std::shared_ptr<ReplaySource> source_;
};

class ReplayTurntable : public ReplayDevice<Turntable> {
 public:
  using ReplayDevice::ReplayDevice;
  TurntableCapabilities capabilities() const override {
    // The fastest motion any rig config asks for: a replay never limits a plan.
    return {.max_speed_deg_s = kTurntableSpeedRange.max,
            .max_accel_deg_s2 = kTurntableAccelRange.max,
            .resolution_deg = 1e-6,
            .can_home = true,
            .settle_s = 0};
  }

 protected:
  Status DoHome(std::chrono::milliseconds) override {
    source_->SetTarget(0);
    position_deg_ = 0;
    return Status::Ok();
  }
  Status DoStartMove(double target_deg, const MotionProfile&) override {
    const RecordedStop* stop = source_->FindStop(target_deg);
    if (!stop) {
      return NotFound(Describe() + ": the recording has no stop at " + std::to_string(target_deg) +
                      " deg (the plan differs from the recorded one)");
    }
    source_->SetTarget(target_deg);
    position_deg_ = stop->measured_deg;
    arrival_ = Clock::now() +
               std::chrono::duration_cast<Clock::duration>(
                   std::chrono::duration<double>(source_->Scaled(stop->seconds_since_previous)));
    SetState(DeviceState::kBusy);
    return Status::Ok();
  }
  Result<TurntableStatus> DoReadStatus() override {
    TurntableStatus s;
    s.position_deg = position_deg_;
    s.target_deg = source_->Target();
    s.in_position = Clock::now() >= arrival_;
    s.moving = !s.in_position;
    s.homed = true;
    return s;
  }
  Status DoWaitInPosition(std::chrono::milliseconds timeout) override {
    if (arrival_ > Clock::now() + timeout)
      return Timeout(Describe() + ": recorded move is longer than the timeout");
    std::this_thread::sleep_until(arrival_);
    SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status DoStop() override {
    arrival_ = Clock::now();
    return Status::Ok();
  }

 private:
  double position_deg_ = 0;
  Clock::time_point arrival_ = Clock::now();
};

class ReplayLight : public ReplayDevice<Light> {
 public:
  using ReplayDevice::ReplayDevice;
  LightCapabilities capabilities() const override { return {.dimmable = true}; }

 protected:
  Status DoSetOn(bool on) override { return DoSetLevel(on ? 1 : 0); }
  Status DoSetLevel(double level) override {
    level_ = level;
    source_->SetLight(info().name, level);
    return Status::Ok();
  }
  Result<bool> DoIsOn() override { return level_ > 0; }

 private:
  double level_ = 0;
};

class ReplayTriggerLine : public ReplayDevice<TriggerLine> {
 public:
  using ReplayDevice::ReplayDevice;

 protected:
  Status DoPulse(std::chrono::microseconds) override {
    source_->triggers.Fire(info().name);
    return Status::Ok();
  }
  Status DoSet(bool active) override {
    if (active) source_->triggers.Fire(info().name);
    return Status::Ok();
  }
};

class ReplayInputLine : public ReplayDevice<InputLine> {
 public:
  using ReplayDevice::ReplayDevice;

 protected:
  Result<bool> DoIsActive() override { return false; }
  void DoOnChange(std::function<void(bool)>) override {}
};

class ReplayCamera : public ReplayDevice<Camera> {
 public:
  using ReplayDevice::ReplayDevice;
  ~ReplayCamera() override { Unsubscribe(); }
  CameraCapabilities capabilities() const override {
    const auto it = source_->sizes.find(info().serial);
    const auto size = it == source_->sizes.end() ? std::pair<int, int>{0, 0} : it->second;
    return {.width_px = size.first,
            .height_px = size.second,
            .formats = {PixelFormat::kEncoded},
            .min_exposure_s = 0,
            .max_exposure_s = 3600,
            .line_trigger = true,
            .readout_s = 0,
            .download_s = 0};
  }

 protected:
  Status DoConfigure(const CaptureSettings& settings) override {
    settings_ = settings;
    return Status::Ok();
  }
  Status DoArm() override {
    Unsubscribe();
    if (settings_.trigger == TriggerSource::kLine) {
      line_ = settings_.trigger_line;
      subscription_ = source_->triggers.Subscribe(line_, [this] { OnTrigger(); });
    }
    return Status::Ok();
  }
  Status DoDisarm() override {
    Unsubscribe();
    std::lock_guard<std::mutex> lock(mutex_);
    pending_.clear();
    return Status::Ok();
  }
  Status DoSoftwareTrigger() override {
    OnTrigger();
    return Status::Ok();
  }
  // The replay's trigger bus hands this camera each pulse with its exact time.
  void DoLineTriggerSent(int64_t) override {}
  Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) override {
    Pending next;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!cv_.wait_for(lock, timeout, [this] { return !pending_.empty(); })) {
        return Timeout(Describe() + ": no frame within " + std::to_string(timeout.count()) + " ms");
      }
      next = pending_.front();
      pending_.pop_front();
    }
    std::this_thread::sleep_until(next.ready);
    if (!next.frame) {
      return NotFound(Describe() + ": the recording has no frame of this camera at " +
                      std::to_string(next.angle_deg) + " deg under the current light state");
    }
    HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                        ReadFileBytes(next.frame->path, next.frame->bytes));
    if (Sha256Hex(bytes.data(), bytes.size()) != next.frame->sha256)
      return CorruptData(next.frame->path + ": changed since the replay verified it");
    Frame f;
    f.camera_serial = info().serial;
    f.sequence = next.sequence;
    f.format = PixelFormat::kEncoded;
    f.encoding = next.frame->extension;
    f.data = std::move(bytes);
    f.exposure_s = next.frame->exposure_s;
    f.gain_db = next.frame->gain_db;
    f.trigger_time_ns = next.trigger_ns;
    f.received_time_ns = SteadyNowNs();
    return f;
  }

 private:
  struct Pending {
    const RecordedFrame* frame = nullptr;
    double angle_deg = 0;
    uint64_t sequence = 0;
    int64_t trigger_ns = 0;
    Clock::time_point ready;
  };
  void OnTrigger() {
    Pending p;
    p.angle_deg = source_->Target();
    p.frame = source_->FindFrame(info().serial, p.angle_deg, source_->Lights());
    p.trigger_ns = SteadyNowNs();
    const double delay = p.frame ? source_->Scaled(p.frame->download_s) : 0;
    p.ready = Clock::now() +
              std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(delay));
    std::lock_guard<std::mutex> lock(mutex_);
    p.sequence = sequence_++;
    pending_.push_back(p);
    cv_.notify_all();
  }
  void Unsubscribe() {
    if (subscription_ != 0) source_->triggers.Unsubscribe(line_, subscription_);
    subscription_ = 0;
  }

  CaptureSettings settings_;
  std::string line_;
  int subscription_ = 0;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Pending> pending_;
  uint64_t sequence_ = 0;
};

template <typename Interface, typename Impl>
void AddReplay(DeviceRegistry* registry, DeviceKind kind, const std::string& model,
               std::shared_ptr<ReplaySource> source) {
  registry->AddBackend<Interface>(
      kind, "replay", [source, model](const DeviceConfig& c) -> Result<std::unique_ptr<Interface>> {
        return std::unique_ptr<Interface>(std::make_unique<Impl>(c.Info(model), source));
      });
}

}  // namespace

void RegisterReplayBackends(DeviceRegistry* registry, std::shared_ptr<ReplaySource> source) {
  AddReplay<Turntable, ReplayTurntable>(registry, DeviceKind::kTurntable, "replayed turntable",
                                        source);
  AddReplay<Light, ReplayLight>(registry, DeviceKind::kLight, "replayed LED panel", source);
  AddReplay<TriggerLine, ReplayTriggerLine>(registry, DeviceKind::kTriggerLine,
                                            "replayed trigger line", source);
  AddReplay<InputLine, ReplayInputLine>(registry, DeviceKind::kInputLine, "replayed input line",
                                        source);
  AddReplay<Camera, ReplayCamera>(registry, DeviceKind::kCamera, "replayed camera", source);
}

}  // namespace hairrig
