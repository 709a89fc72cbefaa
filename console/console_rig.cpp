#include "console/console_rig.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>

#include "console/preview_image.h"
#include "core/clock.h"
#include "core/frame_sink.h"
#include "core/log.h"
#include "core/version.h"
#include "rig/capture_and_process.h"
#include "rig/capture_control.h"
#include "rig/replay_capture.h"
#include "rig/rig_config.h"
#include "rig/safe_names.h"

namespace hairrig {

namespace fs = std::filesystem;

// Each stored frame of the running capture: its thumbnail kept for the page,
// a "view" event, and the camera's preview.
class ConsoleFrameSink : public FrameSink {
 public:
  ConsoleFrameSink(ConsoleRig& console, std::string id) : console_(console), id_(std::move(id)) {}
  void OnFrameStored(const StoredFrame& frame) override {
    console_.OnViewStored(id_, frame.view, frame.camera_name, frame.image);
  }

 private:
  ConsoleRig& console_;
  const std::string id_;
};

Status ConsoleRigOptions::Check() const {
  if (captures_dir.empty())
    return InvalidArgument("captures_dir (--captures, the folder of captures) is required");
  HR_RETURN_IF_ERROR(live.Check().WithContext("live"));
  if (threads < 1) return InvalidArgument("threads must be at least 1");
  if (thumbnail_width_px < 16 || thumbnail_width_px > 4096) {
    return InvalidArgument("thumbnail_width_px must be in [16, 4096], got " +
                           std::to_string(thumbnail_width_px));
  }
  return Status::Ok();
}

ConsoleRig::ConsoleRig(ConsoleRigOptions options, EventHub& events)
    : options_(std::move(options)),
      events_(events),
      archive_(options_.captures_dir),
      live_(events, options_.live) {}

ConsoleRig::~ConsoleRig() { Shutdown(); }

const char* ConsoleRig::BusyName(Busy busy) {
  switch (busy) {
    case Busy::kIdle:
      return "idle";
    case Busy::kCapturing:
      return "capturing";
    case Busy::kProcessing:
      return "processing";
    case Busy::kReplaying:
      return "replaying";
  }
  return "idle";
}

Status ConsoleRig::Start() {
  HR_RETURN_IF_ERROR(options_.Check());
  std::error_code ec;
  fs::create_directories(options_.captures_dir, ec);
  if (ec)
    return IoError(options_.captures_dir + ": cannot create the folder of captures (" +
                   ec.message() + ")");
  std::string path = options_.config_path;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, DefaultRigConfigPath());
  }
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadRigConfig(path));
  HR_ASSIGN_OR_RETURN(rig_, BuildRig(config));
  HR_ASSIGN_OR_RETURN(plan_, ReadCapturePlan(config.root, rig_->devices));
  if (!rig_->devices.turntable) return FailedPrecondition(path + ": the rig has no turntable");
  plan_lower_bound_s_ = PlanLowerBoundS(plan_, rig_->devices);
  if (const Status opened = rig_->devices.OpenAll(); !opened.ok())
    LogWarning("console: " + opened.ToString() + " (see the devices panel)");
  for (const auto& light : rig_->devices.lights) lights_on_[light->info().name] = false;
  LightsOffAndStop();
  WatchSafetyInputs();
  StartLiveView();
  return Status::Ok();
}

void ConsoleRig::Shutdown() {
  std::shared_ptr<CaptureControl> control;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    control = control_;
  }
  if (control) control->RequestStop("the console is shutting down");
  if (worker_.joinable()) worker_.join();
  StopLiveView();
  if (rig_) {
    for (const auto& line : rig_->devices.input_lines) line->OnChange(nullptr);
    rig_->devices.CloseAll();
  }
}

Status ConsoleRig::CheckDevicesFree(const char* what, bool moves) const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (busy_ == Busy::kCapturing)
    return FailedPrecondition(std::string(what) +
                              ": a capture is using the devices; wait for it or stop it");
  if (moves && estop_active_)
    return FailedPrecondition(std::string(what) + ": the e-stop is active (" + estop_reason_ +
                              "); check the rig, then release it");
  return Status::Ok();
}

nlohmann::json ConsoleRig::State() {
  nlohmann::json state = {{"version", HairrigVersion()},
                          {"rig", {{"name", rig_->config.name}, {"config", rig_->config.path}}}};
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state["estop"] = {{"active", estop_active_}, {"reason", estop_reason_}};
    state["busy"] = BusyName(busy_);
    state["capture"] = capture_;
    state["lights"] = lights_on_;
  }
  const Result<TurntableStatus> table = rig_->devices.turntable->state() == DeviceState::kReady
                                            ? rig_->devices.turntable->ReadStatus()
                                            : Result<TurntableStatus>(Unavailable(""));
  state["turntable"] = {
      {"angle_deg", table.ok() ? nlohmann::json(table->position_deg) : nlohmann::json(nullptr)}};
  return state;
}

void ConsoleRig::PublishState() { events_.Publish("state", State()); }

nlohmann::json ConsoleRig::Devices() {
  const bool idle = CheckDevicesFree("devices", false).ok();
  std::unique_lock<std::mutex> lock(rig_mutex_, std::defer_lock);
  if (idle) lock.lock();
  nlohmann::json rows = nlohmann::json::array();
  for (Device* d : rig_->devices.All()) {
    const DeviceInfo& info = d->info();
    std::string health = "in use by the capture";
    if (idle) {
      const Status s = d->state() == DeviceState::kClosed || d->state() == DeviceState::kFaulted
                           ? FailedPrecondition("not open: reconnect it")
                           : d->HealthCheck();
      health = s.ok() ? "ok" : s.message();
    }
    rows.push_back({{"name", info.name},
                    {"kind", DeviceKindName(info.kind)},
                    {"backend", info.backend},
                    {"serial", info.serial},
                    {"model", info.model},
                    {"state", DeviceStateName(d->state())},
                    {"health", health}});
  }
  return {{"devices", rows}};
}

Result<nlohmann::json> ConsoleRig::Reconnect(const std::string& device_name) {
  HR_RETURN_IF_ERROR(CheckDevicesFree("reconnect", false));
  Device* device = nullptr;
  for (Device* d : rig_->devices.All()) {
    if (d->info().name == device_name) device = d;
  }
  if (!device) return NotFound("no device named '" + device_name + "' in the rig config");
  StopLiveView();
  Status s;
  {
    std::lock_guard<std::mutex> lock(rig_mutex_);
    (void)device->Close();
    s = device->Open();
  }
  StartLiveView();
  if (!s.ok()) return s;
  const nlohmann::json all = Devices();
  for (const nlohmann::json& row : all["devices"]) {
    if (row["name"] == device_name) return row;
  }
  return Internal("device '" + device_name + "' vanished");
}

bool ConsoleRig::HasCamera(const std::string& camera_name) const {
  for (const auto& c : rig_->devices.cameras) {
    if (c->info().name == camera_name) return true;
  }
  return false;
}

nlohmann::json ConsoleRig::Cameras() {
  nlohmann::json cameras = nlohmann::json::array();
  for (const auto& c : rig_->devices.cameras) {
    const CameraCapabilities caps = c->capabilities();
    const auto [exposure_s, gain_db] = live_.ExposureOf(c->info().name);
    cameras.push_back({{"name", c->info().name},
                       {"serial", c->info().serial},
                       {"width_px", caps.width_px},
                       {"height_px", caps.height_px},
                       {"exposure_s", exposure_s},
                       {"gain_db", gain_db},
                       {"min_exposure_s", caps.min_exposure_s},
                       {"max_exposure_s", caps.max_exposure_s},
                       {"live", live_.PreviewJson(c->info().name)}});
  }
  return {{"cameras", cameras}};
}

Result<nlohmann::json> ConsoleRig::SetCameraExposure(const std::string& camera_name,
                                                     std::optional<double> exposure_s,
                                                     std::optional<double> gain_db) {
  Camera* camera = nullptr;
  for (const auto& c : rig_->devices.cameras) {
    if (c->info().name == camera_name) camera = c.get();
  }
  if (!camera) return NotFound("no camera named '" + camera_name + "'");
  auto [exposure, gain] = live_.ExposureOf(camera_name);
  const CameraCapabilities caps = camera->capabilities();
  if (exposure_s) {
    if (!std::isfinite(*exposure_s) || *exposure_s < caps.min_exposure_s ||
        *exposure_s > caps.max_exposure_s)
      return OutOfRange("exposure_s: " + std::to_string(*exposure_s) + " s is outside " +
                        camera->Describe() + "'s range [" + std::to_string(caps.min_exposure_s) +
                        ", " + std::to_string(caps.max_exposure_s) + "] s");
    exposure = *exposure_s;
  }
  if (gain_db) {
    if (!std::isfinite(*gain_db) || *gain_db < 0 || *gain_db > 48)
      return OutOfRange("gain_db: must be in [0, 48] dB");
    gain = *gain_db;
  }
  live_.SetExposure(camera_name, exposure, gain);
  const nlohmann::json all = Cameras();
  for (const nlohmann::json& c : all["cameras"]) {
    if (c["name"] == camera_name) return c;
  }
  return Internal("camera '" + camera_name + "' vanished");
}

Result<nlohmann::json> ConsoleRig::SetLights(const std::map<std::string, bool>& on) {
  HR_RETURN_IF_ERROR(CheckDevicesFree("lights", true));
  {
    std::lock_guard<std::mutex> lock(rig_mutex_);
    for (const auto& [name, value] : on) {
      Light* light = nullptr;
      for (const auto& l : rig_->devices.lights) {
        if (l->info().name == name) light = l.get();
      }
      if (!light) return NotFound("no light named '" + name + "'");
      HR_RETURN_IF_ERROR(light->SetOn(value));
      std::lock_guard<std::mutex> state_lock(state_mutex_);
      lights_on_[name] = value;
    }
  }
  PublishState();
  std::lock_guard<std::mutex> state_lock(state_mutex_);
  return nlohmann::json{{"lights", lights_on_}};
}

Result<nlohmann::json> ConsoleRig::Jog(double degrees) {
  if (!std::isfinite(degrees) || std::abs(degrees) > 360)
    return InvalidArgument("degrees: a relative turn in [-360, 360]");
  HR_RETURN_IF_ERROR(CheckDevicesFree("jog", true));
  std::lock_guard<std::mutex> lock(rig_mutex_);
  Turntable& table = *rig_->devices.turntable;
  HR_ASSIGN_OR_RETURN(const TurntableStatus now, table.ReadStatus());
  const double target = now.position_deg + degrees;
  const double expected_s =
      (MoveDurationS(degrees, plan_.motion) + table.capabilities().settle_s) * table.time_scale();
  HR_RETURN_IF_ERROR(
      table.MoveTo(target, plan_.motion,
                   std::chrono::milliseconds(static_cast<int64_t>(1000 * (expected_s + 30)))));
  HR_ASSIGN_OR_RETURN(const TurntableStatus reached, table.ReadStatus());
  return nlohmann::json{{"angle_deg", reached.position_deg}};
}

Result<nlohmann::json> ConsoleRig::Home() {
  HR_RETURN_IF_ERROR(CheckDevicesFree("home", true));
  std::lock_guard<std::mutex> lock(rig_mutex_);
  Turntable& table = *rig_->devices.turntable;
  HR_RETURN_IF_ERROR(table.Home(std::chrono::seconds(120)));
  HR_ASSIGN_OR_RETURN(const TurntableStatus reached, table.ReadStatus());
  return nlohmann::json{{"angle_deg", reached.position_deg}};
}

nlohmann::json ConsoleRig::Plan() const {
  nlohmann::json cameras = nlohmann::json::array();
  for (const auto& c : rig_->devices.cameras) cameras.push_back(c->info().name);
  return {{"views", plan_.views.size()},
          {"stops", plan_.stops.size()},
          {"cameras", cameras},
          {"exposure_s", plan_.camera_settings.exposure_s},
          {"gain_db", plan_.camera_settings.gain_db},
          {"expected_s", plan_lower_bound_s_}};
}

void ConsoleRig::LightsOffAndStop() {
  (void)rig_->devices.turntable->Stop();
  for (const auto& light : rig_->devices.lights) {
    if (light->state() == DeviceState::kReady) (void)light->SetOn(false);
  }
  std::lock_guard<std::mutex> lock(state_mutex_);
  for (auto& [name, on] : lights_on_) on = false;
}

void ConsoleRig::WatchSafetyInputs() {
  for (const auto& line : rig_->devices.input_lines) {
    InputLine* input = line.get();
    input->OnChange([this, input](bool active) {
      if (active) EStop(DescribeSafetyStop(*input));
    });
  }
}

void ConsoleRig::StartLiveView() {
  std::vector<Camera*> cameras;
  for (const auto& c : rig_->devices.cameras) {
    if (c->state() == DeviceState::kReady) cameras.push_back(c.get());
  }
  live_.Start(cameras, plan_.camera_settings);
}

void ConsoleRig::StopLiveView() { live_.Stop(); }

void ConsoleRig::RunOnWorker(std::function<void()> job) {
  if (worker_.joinable()) worker_.join();  // the previous job has ended: the rig was idle
  worker_ = std::thread(std::move(job));
}

namespace {

// "20261127-071205": the UTC time in capture ids.
std::string UtcStamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%d-%H%M%S", &utc);
  return text;
}

}  // namespace

// A capture's status as the page shows it, before its first progress.
nlohmann::json ConsoleRig::NewCaptureStatus(const std::string& id, const std::string& subject,
                                            int views_done, int views_total,
                                            const std::string& step) const {
  return {{"id", id},
          {"subject", subject},
          {"status", "running"},
          {"views_done", views_done},
          {"views_total", views_total},
          {"stop", 0},
          {"stops_total", plan_.stops.size()},
          {"step", step},
          {"eta_s", plan_lower_bound_s_},
          {"faults", 0},
          {"message", ""},
          {"calibration", nullptr}};
}

Status ConsoleRig::ClaimForCapture(const std::string& what, nlohmann::json status) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (busy_ != Busy::kIdle)
    return FailedPrecondition(what + ": the rig is " + BusyName(busy_) + "; wait for it");
  if (estop_active_)
    return FailedPrecondition(what + ": the e-stop is active (" + estop_reason_ +
                              "); release it first");
  busy_ = Busy::kCapturing;
  control_ = std::make_shared<CaptureControl>();
  capture_ = std::move(status);
  thumbnails_.clear();
  last_progress_views_ = -1;
  last_faults_ = 0;
  return Status::Ok();
}

Result<std::string> ConsoleRig::StartCapture(const std::string& subject, bool calibrate,
                                             bool reconstruct) {
  if (reconstruct && !calibrate) return InvalidArgument("reconstruct needs calibrate");
  HR_ASSIGN_OR_RETURN(const std::string folder, SubjectFolderName(subject));
  std::string id = folder.substr(0, 100) + "-" + UtcStamp();
  for (int n = 2; fs::exists(fs::path(options_.captures_dir) / id); ++n)
    id = folder.substr(0, 100) + "-" + UtcStamp() + "-" + std::to_string(n);
  HR_RETURN_IF_ERROR(
      ClaimForCapture("a capture cannot start",
                      NewCaptureStatus(id, subject, 0, static_cast<int>(plan_.views.size()),
                                       "opening the devices")));
  RunOnWorker([this, id, subject, calibrate, reconstruct] {
    RunCaptureJob(id, subject, false, calibrate, reconstruct);
  });
  return id;
}

Result<std::string> ConsoleRig::ResumeCapture(const std::string& id, bool calibrate,
                                              bool reconstruct) {
  if (reconstruct && !calibrate) return InvalidArgument("reconstruct needs calibrate");
  HR_ASSIGN_OR_RETURN(const ArchiveEntry entry, archive_.Entry(id));
  if (entry.status == "complete")
    return FailedPrecondition("capture '" + id + "' is complete: nothing to resume");
  HR_RETURN_IF_ERROR(ClaimForCapture(
      "cannot resume",
      NewCaptureStatus(id, entry.subject, entry.views_completed, entry.views_planned, "resuming")));
  RunOnWorker(
      [this, id, calibrate, reconstruct] { RunCaptureJob(id, "", true, calibrate, reconstruct); });
  return id;
}

void ConsoleRig::RunCaptureJob(const std::string& id, const std::string& subject, bool resume,
                               bool calibrate, bool reconstruct) {
  PublishState();
  StopLiveView();
  {
    std::lock_guard<std::mutex> lock(rig_mutex_);
    for (const auto& line : rig_->devices.input_lines) line->OnChange(nullptr);
    rig_->devices.CloseAll();
  }
  ConsoleFrameSink sink(*this, id);
  CaptureAndProcessOptions o;
  o.out_dir = resume ? (fs::path(options_.captures_dir) / id).string() : options_.captures_dir;
  o.subject = subject;
  o.folder_name = id;
  o.resume = resume;
  o.calibrate = calibrate;
  o.reconstruct = reconstruct;
  o.threads = options_.threads;
  o.rig = rig_.get();
  o.sink = &sink;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    o.control = control_;
  }
  bool captured = false;
  o.on_progress = [this, id](const CaptureProgress& p) { OnProgress(id, p); };
  o.on_captured = [this, id, &captured](const CaptureSummary& s) {
    captured = true;
    ReturnDevicesToConsole();
    nlohmann::json end;
    {
      std::lock_guard<std::mutex> lock(state_mutex_);
      capture_["status"] = s.status;
      capture_["message"] = s.message;
      capture_["views_done"] = s.views_completed;
      capture_["eta_s"] = 0;
      capture_["faults"] = s.faults;
      capture_["step"] = s.status;
      capture_["wall_s"] = s.wall_s;
      capture_["lower_bound_s"] = s.lower_bound_s;
      busy_ = Busy::kProcessing;  // until CaptureAndProcess returns
      end = capture_;
    }
    events_.Publish("capture_end", end);
    PublishState();
  };
  const Result<CaptureAndProcessSummary> result = CaptureAndProcess(o);
  nlohmann::json processed = {{"id", id}, {"calibration", nullptr}, {"reconstruction", false}};
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    if (!result.ok()) {
      if (!captured) capture_["status"] = "failed";
      capture_["message"] = result.status().ToString();
    } else if (result->calibration) {
      const CalibratedFolder& c = result->calibration->calibration;
      capture_["calibration"] = {{"verdict", c.verdict.name()}, {"rms_px", c.result.rms_px}};
      processed["calibration"] = capture_["calibration"];
      processed["reconstruction"] = result->reconstruction.has_value();
    }
  }
  if (!captured) {
    nlohmann::json end;
    {
      std::lock_guard<std::mutex> lock(state_mutex_);
      end = capture_;
    }
    events_.Publish("capture_end", end);
  }
  if (!result.ok()) LogWarning("console: capture " + id + ": " + result.status().ToString());
  events_.Publish("processed", processed);
  if (!captured) ReturnDevicesToConsole();
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    busy_ = Busy::kIdle;
    control_.reset();
  }
  PublishState();
}

// After a capture (which closed the devices): open them again for the live
// view, the lights and the turntable.
void ConsoleRig::ReturnDevicesToConsole() {
  {
    std::lock_guard<std::mutex> lock(rig_mutex_);
    if (const Status opened = rig_->devices.OpenAll(); !opened.ok())
      LogWarning("console: " + opened.ToString() + " (see the devices panel)");
  }
  WatchSafetyInputs();
  StartLiveView();
}

void ConsoleRig::OnProgress(const std::string& id, const CaptureProgress& p) {
  const int64_t now_ns = SteadyNowNs();
  nlohmann::json progress, fault;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    capture_["views_done"] = p.views_done;
    capture_["views_total"] = p.views_total;
    capture_["stop"] = p.stop;
    capture_["stops_total"] = p.stops_total;
    capture_["step"] = p.step;
    capture_["eta_s"] = p.eta_s;
    capture_["faults"] = p.faults;
    if (p.faults > last_faults_) {
      last_faults_ = p.faults;
      fault = {{"id", id}, {"what", p.last_fault}, {"faults", p.faults}};
    }
    // At most ten a second, but every stored view.
    if (p.views_done != last_progress_views_ || now_ns - last_progress_ns_ >= 100'000'000) {
      last_progress_views_ = p.views_done;
      last_progress_ns_ = now_ns;
      progress = capture_;
    }
  }
  if (!fault.is_null()) events_.Publish("fault", fault);
  if (!progress.is_null()) events_.Publish("progress", progress);
}

void ConsoleRig::OnViewStored(const std::string& id, int view, const std::string& camera,
                              const cv::Mat& image) {
  const cv::Mat small = DownscaleForPreview(image, options_.live.max_width_px);
  live_.Offer(camera, small, "capture");
  Result<std::vector<uint8_t>> thumb = EncodePreviewJpeg(small, options_.thumbnail_width_px);
  if (!thumb.ok()) return;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    thumbnails_[{id, view}] = std::move(*thumb);
  }
  events_.Publish(
      "view", {{"id", id},
               {"view", view},
               {"camera", camera},
               {"thumb", "/api/captures/" + id + "/views/" + std::to_string(view) + "/thumb.jpg"}});
}

Result<std::string> ConsoleRig::ReplayCapture(const std::string& id) {
  HR_ASSIGN_OR_RETURN(const std::string dir, archive_.CaptureDir(id));
  const std::string replay_id = id + "-replay";
  HR_RETURN_IF_ERROR(CheckCaptureId(replay_id));
  if (fs::exists(fs::path(options_.captures_dir) / replay_id))
    return FailedPrecondition("capture '" + replay_id + "' exists already");
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    if (busy_ != Busy::kIdle)
      return FailedPrecondition(std::string("cannot replay: the rig is ") + BusyName(busy_));
    busy_ = Busy::kReplaying;
  }
  RunOnWorker([this, dir, replay_id] {
    PublishState();
    ReplayCaptureOptions o;
    o.recorded_dir = dir;
    o.out_dir = (fs::path(options_.captures_dir) / replay_id).string();
    const Result<ReplayCaptureSummary> result = hairrig::ReplayCapture(o);
    nlohmann::json end = {
        {"id", replay_id},
        {"status", result.ok() ? result->capture.status : "failed"},
        {"message", result.ok() ? result->capture.message : result.status().ToString()}};
    events_.Publish("capture_end", end);
    {
      std::lock_guard<std::mutex> lock(state_mutex_);
      busy_ = Busy::kIdle;
    }
    PublishState();
  });
  return replay_id;
}

Status ConsoleRig::StopCapture(const std::string& who) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (busy_ != Busy::kCapturing || !control_) return FailedPrecondition("no capture is running");
  control_->RequestStop("stop pressed by " + who);
  capture_["step"] = "stopping after this stop";
  return Status::Ok();
}

nlohmann::json ConsoleRig::EStop(const std::string& who) {
  std::shared_ptr<CaptureControl> control;
  std::string reason;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    estop_active_ = true;
    estop_reason_ = "e-stop by " + who;
    reason = estop_reason_;
    control = control_;
  }
  if (control) control->EmergencyStop(reason);
  LightsOffAndStop();
  LogWarning("console: " + reason + ": turntable stopped, lights off");
  PublishState();
  std::lock_guard<std::mutex> lock(state_mutex_);
  return {{"active", estop_active_}, {"reason", estop_reason_}};
}

Status ConsoleRig::ReleaseEStop() {
  // A safety input that cannot be read counts as pressed (drivers/input_line.h).
  for (const auto& line : rig_->devices.input_lines) {
    const Result<bool> active = line->IsActive();
    if (!active.ok()) {
      return FailedPrecondition(line->Describe() + " cannot be read (" + active.status().message() +
                                "): check its wiring and reconnect it, then release the e-stop");
    }
    if (*active)
      return FailedPrecondition(line->Describe() + " is still active: release it on the rig first");
  }
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    estop_active_ = false;
    estop_reason_.clear();
  }
  PublishState();
  return Status::Ok();
}

std::optional<LivePreview> ConsoleRig::Preview(const std::string& camera_name) const {
  return live_.Latest(camera_name);
}

std::optional<std::vector<uint8_t>> ConsoleRig::CachedThumbnail(const std::string& id,
                                                                int view) const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  const auto it = thumbnails_.find({id, view});
  if (it == thumbnails_.end()) return std::nullopt;
  return it->second;
}

}  // namespace hairrig
