#include "sim_hw/sim_devices.h"

#include <cmath>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "drivers/always_present_device.h"
#include "drivers/camera_support.h"
#include "drivers/polled_turntable.h"
#include "drivers/trigger_bus.h"
#include "sim_hw/quota_storage.h"
#include "sim_hw/sim_turntable_controller.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

namespace {

// Trapezoidal (or triangular) move: position after `t` seconds of a move of
// `distance` deg at the given speed and acceleration; duration in *duration_s.
double TrapezoidPosition(double distance, const MotionProfile& p, double t) {
  const double d = std::abs(distance);
  const double speed = p.speed_deg_s, accel = p.accel_deg_s2;
  const double duration = MoveDurationS(distance, p);
  const double t_acc = std::min(speed / accel, 0.5 * duration);
  const double peak = accel * t_acc;
  double pos;
  if (t < t_acc)
    pos = 0.5 * accel * t * t;
  else if (t < duration - t_acc)
    pos = 0.5 * peak * t_acc + peak * (t - t_acc);
  else
    pos = d - 0.5 * accel * std::pow(std::max(0.0, duration - t), 2);
  return std::copysign(std::min(pos, d), distance);
}
}  // namespace

class SimWorld {
 public:
  SimWorld(std::unique_ptr<Renderer> renderer, SimWorldOptions options)
      : renderer_(std::move(renderer)),
        options_(std::move(options)),
        turntable_controller_(std::make_unique<SimTurntableController>(*this)) {
    for (const SceneLight& l : renderer_->scene().lights) light_levels_[l.name] = 0.0;
  }
  ~SimWorld() {
    if (estop_timer_.joinable()) estop_timer_.join();
  }

  // --- fault injection --------------------------------------------------
  // Counts one more event of `device` ("" for the turntable) and returns the
  // first configured fault of `kind` that hits it, or nullptr.
  const SimFault* NextEventFault(const std::string& device,
                                 std::initializer_list<SimFaultKind> kinds) {
    std::lock_guard<std::mutex> lock(mutex_);
    const int event = ++event_counts_[device];
    for (const SimFault& f : options_.faults) {
      for (SimFaultKind k : kinds) {
        if (f.kind == k && f.device == device && f.Hits(event)) return &f;
      }
    }
    return nullptr;
  }
  const SimFault* FindFault(SimFaultKind kind) const {
    for (const SimFault& f : options_.faults) {
      if (f.kind == kind) return &f;
    }
    return nullptr;
  }
  const Renderer& renderer() const { return *renderer_; }
  const Scene& scene() const { return renderer_->scene(); }
  double time_scale() const { return options_.time_scale; }
  bool noise() const { return options_.noise; }

  // Sleeps `sim_seconds` of simulated time.
  void SleepSim(double sim_seconds) const {
    if (sim_seconds > 0)
      std::this_thread::sleep_for(std::chrono::duration<double>(sim_seconds * options_.time_scale));
  }
  double SimSecondsSince(Clock::time_point t0) const {
    return std::chrono::duration<double>(Clock::now() - t0).count() / options_.time_scale;
  }

  // --- turntable motion -------------------------------------------------
  void StartMove(double target_deg, const MotionProfile& p) {
    std::lock_guard<std::mutex> lock(mutex_);
    move_start_deg_ = AngleLocked();
    move_target_deg_ = target_deg;
    move_profile_ = p;
    move_start_ = Clock::now();
    stuck_ = false;
  }
  // Simulated seconds until the platform stops moving (settle excluded).
  double MotionSecondsLeft() const {
    std::lock_guard<std::mutex> lock(mutex_);
    const double duration = MoveDurationS(move_target_deg_ - move_start_deg_, move_profile_);
    return std::max(0.0, duration - SimSecondsSince(move_start_));
  }
  // The current move never sets the in-position flag (the controller hunts
  // around the target: a following-error loop that never settles).
  void JamMove() {
    std::lock_guard<std::mutex> lock(mutex_);
    stuck_ = true;
  }
  double AngleDeg() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return AngleLocked();
  }
  // Simulated seconds until in position (move plus settle); 0 when there.
  double SecondsToInPosition() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stuck_) return std::numeric_limits<double>::infinity();
    const double duration = MoveDurationS(move_target_deg_ - move_start_deg_, move_profile_);
    return std::max(0.0, duration + scene().turntable_settle_s - SimSecondsSince(move_start_));
  }
  void StopMotion() {
    std::lock_guard<std::mutex> lock(mutex_);
    move_start_deg_ = move_target_deg_ = AngleLocked();
    move_start_ = Clock::now();
    stuck_ = false;
  }

  // --- safety inputs ----------------------------------------------------
  using InputFn = std::function<void(bool)>;
  void SetInputCallback(const std::string& line, InputFn fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (fn)
      input_callbacks_[line] = std::move(fn);
    else
      input_callbacks_.erase(line);
  }
  bool InputActive() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return input_active_;
  }
  void SetInputActive(bool active) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (input_active_ == active) return;
      input_active_ = active;
    }
    NotifyInputs(active);
  }
  // The safety inputs' wiring is broken (an input_lost fault): they cannot be
  // read from then on.
  bool InputsLost() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return inputs_lost_;
  }
  // `after_s` device seconds from now, from another thread: presses the e-stop
  // (kEstop) or breaks the inputs' wiring (kInputLost), telling the lines'
  // callbacks `true` either way.
  void ScheduleSafetyEvent(SimFaultKind kind, double after_s) {
    if (estop_timer_.joinable()) estop_timer_.join();
    estop_timer_ = std::thread([this, kind, after_s] {
      SleepSim(after_s);
      if (kind == SimFaultKind::kInputLost) {
        std::lock_guard<std::mutex> lock(mutex_);
        inputs_lost_ = true;
      }
      NotifyInputs(true);
    });
  }

  // --- lights -----------------------------------------------------------
  Status SetLightLevel(const std::string& name, double level) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = light_levels_.find(name);
    if (it == light_levels_.end()) return NotFound("the scene has no light '" + name + "'");
    it->second = level;
    return Status::Ok();
  }
  double LightLevel(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = light_levels_.find(name);
    return it == light_levels_.end() ? 0.0 : it->second;
  }
  std::vector<double> LightLevels() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<double> levels;
    for (const SceneLight& l : scene().lights) levels.push_back(light_levels_.at(l.name));
    return levels;
  }

  // --- trigger lines ----------------------------------------------------
  TriggerBus& triggers() { return triggers_; }

  SimTurntableController& turntable_controller() { return *turntable_controller_; }

  void SetTruthRecorder(WorldTruthRecorder recorder) {
    std::lock_guard<std::mutex> lock(mutex_);
    truth_recorder_ =
        recorder ? std::make_shared<const WorldTruthRecorder>(std::move(recorder)) : nullptr;
  }
  std::shared_ptr<const WorldTruthRecorder> truth_recorder() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return truth_recorder_;
  }

  // --- the last radiance each scene camera rendered -----------------------
  // A frame of an unchanged world (same turntable angle and light levels) is
  // exposed again from it, with its own noise, instead of rendered again.
  struct CachedRadiance {
    WorldExposure world;
    cv::Mat3f radiance;
  };
  std::shared_ptr<const CachedRadiance> CachedRadianceFor(int scene_camera,
                                                          const WorldExposure& exposure) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = radiance_cache_.find(scene_camera);
    if (it == radiance_cache_.end() || !SameWorld(it->second->world, exposure)) return nullptr;
    return it->second;
  }
  void CacheRadiance(int scene_camera, const WorldExposure& exposure, cv::Mat3f radiance) const {
    auto entry =
        std::make_shared<const CachedRadiance>(CachedRadiance{exposure, std::move(radiance)});
    std::lock_guard<std::mutex> lock(mutex_);
    radiance_cache_[scene_camera] = std::move(entry);
  }

 private:
  static bool SameWorld(const WorldExposure& a, const WorldExposure& b) {
    return std::abs(a.angle_deg - b.angle_deg) < 1e-9 && a.light_levels == b.light_levels;
  }
  void NotifyInputs(bool active) {
    std::vector<InputFn> fns;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto& [name, fn] : input_callbacks_) fns.push_back(fn);
    }
    for (auto& fn : fns) fn(active);
  }
  double AngleLocked() const {
    return move_start_deg_ + TrapezoidPosition(move_target_deg_ - move_start_deg_, move_profile_,
                                               SimSecondsSince(move_start_));
  }

  std::unique_ptr<Renderer> renderer_;
  SimWorldOptions options_;
  mutable std::mutex mutex_;
  double move_start_deg_ = 0, move_target_deg_ = 0;
  MotionProfile move_profile_;
  Clock::time_point move_start_ = Clock::now();
  std::map<std::string, double> light_levels_;
  TriggerBus triggers_;
  bool stuck_ = false;
  std::map<std::string, int> event_counts_;
  std::map<std::string, InputFn> input_callbacks_;
  bool inputs_lost_ = false;
  bool input_active_ = false;
  std::thread estop_timer_;
  std::unique_ptr<SimTurntableController> turntable_controller_;
  std::shared_ptr<const WorldTruthRecorder> truth_recorder_;
  mutable std::map<int, std::shared_ptr<const CachedRadiance>> radiance_cache_;
};

Status SimWorldOptions::Check() const {
  if (!(time_scale > 0) || !std::isfinite(time_scale))
    return InvalidArgument("sim time_scale must be a positive number (1 = real time)");
  for (size_t i = 0; i < faults.size(); ++i) {
    const SimFault& f = faults[i];
    const std::string field = "sim faults[" + std::to_string(i) + "].";
    if (f.at < 0)
      return InvalidArgument(field + "at must be 0 or more, got " + std::to_string(f.at));
    if (f.count < 1)
      return InvalidArgument(field + "count must be at least 1, got " + std::to_string(f.count));
    if (!(f.delay_s >= 0) || !std::isfinite(f.delay_s))
      return InvalidArgument(field + "delay_s must be a finite number of seconds, 0 or more");
  }
  return Status::Ok();
}

Result<std::shared_ptr<SimWorld>> CreateSimWorld(const Scene& scene,
                                                 const SimWorldOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, Renderer::Create(scene));
  return std::make_shared<SimWorld>(std::move(renderer), options);
}
const Renderer& WorldRenderer(const SimWorld& world) { return world.renderer(); }
double WorldTimeScale(const SimWorld& world) { return world.time_scale(); }
double WorldTurntableAngleDeg(const SimWorld& world) { return world.AngleDeg(); }
std::shared_ptr<CaptureStorage> MakeWorldCaptureStorage(const SimWorld& world) {
  const SimFault* full = world.FindFault(SimFaultKind::kDiskFull);
  if (!full) return nullptr;
  QuotaStorageOptions options;
  options.frame_files = full->at;
  return std::make_shared<QuotaStorage>(options);
}
SimTurntableController& WorldTurntableController(SimWorld& world) {
  return world.turntable_controller();
}
TriggerBus& WorldTriggers(SimWorld& world) { return world.triggers(); }
void SetWorldTruthRecorder(SimWorld& world, WorldTruthRecorder recorder) {
  world.SetTruthRecorder(std::move(recorder));
}
Status SetWorldLightLevel(SimWorld& world, const std::string& light, double level) {
  return world.SetLightLevel(light, level);
}

WorldExposure ExposeWorldNow(const SimWorld& world) {
  return {world.AngleDeg(), world.LightLevels(), SteadyNowNs()};
}

Result<cv::Mat> RenderWorldExposure(const SimWorld& world, int scene_camera,
                                    const WorldExposure& exposure, double exposure_s,
                                    double gain_db, uint64_t noise_seed) {
  RenderOptions o;
  o.light_levels = exposure.light_levels;
  o.exposure_s = exposure_s;
  o.gain_db = gain_db;
  o.noise = world.noise();
  o.noise_seed = noise_seed;
  const auto recorder = world.truth_recorder();
  if (!recorder) {  // with a recorder every frame renders its maps
    if (auto cached = world.CachedRadianceFor(scene_camera, exposure)) {
      return world.renderer().Expose(scene_camera, cached->radiance, o);
    }
  }
  o.ground_truth = recorder != nullptr;
  o.keep_radiance = true;
  HR_ASSIGN_OR_RETURN(RenderedView view,
                      world.renderer().Render(scene_camera, exposure.angle_deg, o));
  if (recorder) (*recorder)(scene_camera, exposure.angle_deg, view.truth);
  world.CacheRadiance(scene_camera, exposure, std::move(view.radiance));
  return std::move(view.image);
}

cv::Mat MosaicRGGB(const cv::Mat& bgr) {
  cv::Mat bayer(bgr.rows, bgr.cols, CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int channel = (y % 2 == 0) ? (x % 2 == 0 ? 2 : 1) : (x % 2 == 0 ? 1 : 0);
      bayer.at<uint8_t>(y, x) = p[channel];
    }
  }
  return bayer;
}

uint64_t FrameNoiseSeed(const SimWorld& world, const std::string& serial, uint64_t sequence) {
  return std::hash<std::string>{}(serial) ^ (sequence * 0x9E3779B97F4A7C15ull) ^ world.scene().seed;
}

const SimFault* NextCameraFault(SimWorld& world, const std::string& serial) {
  return world.NextEventFault(serial, {SimFaultKind::kDropFrame, SimFaultKind::kCameraGone,
                                       SimFaultKind::kDownloadTimeout});
}

// --- the turntable controller ------------------------------------------------

const char* TurntableFaultCodeName(TurntableFaultCode code) {
  switch (code) {
    case TurntableFaultCode::kNone:
      return "no fault";
    case TurntableFaultCode::kStall:
      return "a stall (following error)";
    case TurntableFaultCode::kLimit:
      return "a move beyond the speed or acceleration limits";
  }
  return "an unknown fault";
}

TurntableCapabilities SimTurntableController::capabilities() const {
  return {.max_speed_deg_s = 90,
          .max_accel_deg_s2 = 360,
          .resolution_deg = 0.001,
          .can_home = true,
          .settle_s = world_.scene().turntable_settle_s};
}

double SimTurntableController::time_scale() const { return world_.time_scale(); }

TurntableFaultCode SimTurntableController::StartMove(double target_deg, const MotionProfile& p) {
  const TurntableCapabilities caps = capabilities();
  std::optional<SafetyEvent> safety_event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!std::isfinite(target_deg) ||
        !(p.speed_deg_s > 0 && p.speed_deg_s <= caps.max_speed_deg_s) ||
        !(p.accel_deg_s2 > 0 && p.accel_deg_s2 <= caps.max_accel_deg_s2)) {
      fault_ = TurntableFaultCode::kLimit;
      return fault_;
    }
    safety_event = StartMoveLocked(target_deg, p);
    homing_ = false;
  }
  // Outside the lock: the inputs' handlers may call Stop().
  if (safety_event) world_.ScheduleSafetyEvent(safety_event->kind, safety_event->after_s);
  return TurntableFaultCode::kNone;
}

void SimTurntableController::StartHome() {
  std::optional<SafetyEvent> safety_event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    safety_event = StartMoveLocked(
        0.0, {world_.scene().turntable_speed_deg_s, world_.scene().turntable_accel_deg_s2});
    homing_ = true;
  }
  if (safety_event) world_.ScheduleSafetyEvent(safety_event->kind, safety_event->after_s);
}

std::optional<SimTurntableController::SafetyEvent> SimTurntableController::StartMoveLocked(
    double target_deg, const MotionProfile& p) {
  const double move_s = MoveDurationS(target_deg - world_.AngleDeg(), p);
  world_.StartMove(target_deg, p);
  target_deg_ = target_deg;
  stall_after_s_ = -1;
  move_start_ = Clock::now();
  const SimFault* fault =
      world_.NextEventFault("", {SimFaultKind::kTurntableTimeout, SimFaultKind::kTurntableStall,
                                 SimFaultKind::kEstop, SimFaultKind::kInputLost});
  if (!fault) return std::nullopt;
  switch (fault->kind) {
    case SimFaultKind::kTurntableTimeout:
      world_.JamMove();
      break;
    case SimFaultKind::kTurntableStall:
      stall_after_s_ = 0.5 * move_s;
      break;
    case SimFaultKind::kEstop:
    case SimFaultKind::kInputLost:
      return SafetyEvent{fault->kind, 0.2 * move_s};
    default:
      break;
  }
  return std::nullopt;
}

void SimTurntableController::Stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  world_.StopMotion();
  homing_ = false;
  stall_after_s_ = -1;
}

void SimTurntableController::ClearFault() {
  std::lock_guard<std::mutex> lock(mutex_);
  fault_ = TurntableFaultCode::kNone;
}

TurntableControllerStatus SimTurntableController::Poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stall_after_s_ >= 0 && world_.SimSecondsSince(move_start_) >= stall_after_s_) {
    world_.StopMotion();
    fault_ = TurntableFaultCode::kStall;
    stall_after_s_ = -1;
    homing_ = false;
  }
  TurntableControllerStatus s;
  s.position_deg = world_.AngleDeg();
  s.target_deg = target_deg_;
  s.fault = fault_;
  const bool ok = fault_ == TurntableFaultCode::kNone;
  s.in_position = ok && world_.SecondsToInPosition() <= 0;
  s.moving = ok && world_.MotionSecondsLeft() > 0;
  if (homing_ && s.in_position) {
    homed_ = true;
    homing_ = false;
  }
  s.homed = homed_;
  return s;
}

namespace {

// Shared open/close/health behaviour of the simulated devices.
template <typename Base>
class SimDevice : public AlwaysPresentDevice<Base> {
 public:
  SimDevice(DeviceInfo info, std::shared_ptr<SimWorld> world)
      : AlwaysPresentDevice<Base>(std::move(info)), world_(std::move(world)) {}
  double time_scale() const override { return world_->time_scale(); }

 protected:
  std::shared_ptr<SimWorld> world_;
};

class SimTurntable : public SimDevice<PolledTurntable> {
 public:
  SimTurntable(DeviceInfo info, std::shared_ptr<SimWorld> world)
      : SimDevice(std::move(info), world), controller_(world->turntable_controller()) {}
  TurntableCapabilities capabilities() const override { return controller_.capabilities(); }

 protected:
  Status DoHome(std::chrono::milliseconds timeout) override {
    controller_.StartHome();
    MoveStarted(0);
    return DoWaitInPosition(timeout);
  }
  Status DoStartMove(double target_deg, const MotionProfile& p) override {
    HR_RETURN_IF_ERROR(CheckMoveRequest(Describe(), target_deg, p, capabilities()));
    controller_.ClearFault();
    const TurntableFaultCode refused = controller_.StartMove(target_deg, p);
    if (refused != TurntableFaultCode::kNone)
      return Fault(DeviceFault(TurntableFaultCodeName(refused)));
    MoveStarted(target_deg);
    return Status::Ok();
  }
  Result<TurntableStatus> DoReadStatus() override {
    const TurntableControllerStatus c = controller_.Poll();
    TurntableStatus s{.position_deg = c.position_deg,
                      .target_deg = target_deg(),
                      .moving = c.moving,
                      .in_position = c.in_position,
                      .homed = c.homed,
                      .fault = c.fault != TurntableFaultCode::kNone};
    if (s.in_position && state() == DeviceState::kBusy) SetState(DeviceState::kReady);
    return s;
  }
  // Polls like a real driver reading the status register, so that Stop() from
  // another thread (an e-stop) ends the wait at once.
  Status DoWaitInPosition(std::chrono::milliseconds timeout) override {
    return WaitUntilDone(timeout, std::chrono::milliseconds(2), [this]() -> Result<MotionPoll> {
      const TurntableControllerStatus c = controller_.Poll();
      MotionPoll p{.position_deg = c.position_deg, .done = c.in_position, .fault = std::nullopt};
      if (c.fault != TurntableFaultCode::kNone) p.fault = TurntableFaultCodeName(c.fault);
      return p;
    });
  }
  Status DoStop() override {
    controller_.Stop();
    StopRequested();
    return Status::Ok();
  }

 private:
  SimTurntableController& controller_;
};

class SimLight : public SimDevice<Light> {
 public:
  SimLight(DeviceInfo info, std::shared_ptr<SimWorld> world, std::string scene_light)
      : SimDevice(std::move(info), std::move(world)), scene_light_(std::move(scene_light)) {}
  LightCapabilities capabilities() const override { return {.dimmable = true}; }

 protected:
  Status DoSetOn(bool on) override { return DoSetLevel(on ? 1.0 : 0.0); }
  Status DoSetLevel(double level) override {
    if (!(level >= 0 && level <= 1)) return OutOfRange(Describe() + ": level must be within 0..1");
    return world_->SetLightLevel(scene_light_, level);
  }
  Result<bool> DoIsOn() override { return world_->LightLevel(scene_light_) > 0; }
  Status DoClose() override {
    if (state() == DeviceState::kReady) (void)world_->SetLightLevel(scene_light_, 0.0);
    return SimDevice::DoClose();
  }

 private:
  std::string scene_light_;
};

class SimTriggerLine : public SimDevice<TriggerLine> {
 public:
  using SimDevice::SimDevice;

 protected:
  Status DoPulse(std::chrono::microseconds width) override {
    if (width.count() <= 0) return InvalidArgument(Describe() + ": pulse width must be positive");
    world_->triggers().Fire(info().name);  // cameras latch on the rising edge
    std::this_thread::sleep_for(width);
    return Status::Ok();
  }
  Status DoSet(bool active) override {
    if (active && !active_) world_->triggers().Fire(info().name);
    active_ = active;
    return Status::Ok();
  }

 private:
  bool active_ = false;
};

// Once the world's inputs are lost (an input_lost fault), every read fails and
// faults the line, and the line's callback hears `true` after the fault.
class SimInputLine : public SimDevice<InputLine> {
 public:
  using SimDevice::SimDevice;
  ~SimInputLine() override { world_->SetInputCallback(info().name, nullptr); }

 protected:
  Result<bool> DoIsActive() override {
    if (world_->InputsLost()) return Fault(InputLost());
    return world_->InputActive();
  }
  void DoOnChange(std::function<void(bool active)> callback) override {
    if (!callback) {
      world_->SetInputCallback(info().name, nullptr);
      return;
    }
    world_->SetInputCallback(info().name, [this, callback = std::move(callback)](bool active) {
      if (world_->InputsLost()) (void)Fault(InputLost());
      callback(active);
    });
  }

 private:
  static Status InputLost() {
    return Unavailable("the line cannot be read (simulated input_lost fault: wiring broken)");
  }
};

// Renders on a worker thread so that downloads overlap whatever the caller does next.
class SimCamera : public SimDevice<Camera> {
 public:
  SimCamera(DeviceInfo info, std::shared_ptr<SimWorld> world, int scene_camera, std::string line)
      : SimDevice(std::move(info), std::move(world)),
        scene_camera_(scene_camera),
        configured_line_(std::move(line)) {
    settings_.trigger = configured_line_.empty() ? TriggerSource::kSoftware : TriggerSource::kLine;
    settings_.trigger_line = configured_line_;
    settings_.exposure_s = world_->scene().cameras[static_cast<size_t>(scene_camera_)].exposure_s;
  }
  ~SimCamera() override { StopWorker(); }

  CameraCapabilities capabilities() const override {
    const auto& intr = world_->scene().cameras[static_cast<size_t>(scene_camera_)].intrinsics;
    return {.width_px = intr.width_px,
            .height_px = intr.height_px,
            .formats = {PixelFormat::kRgb8, PixelFormat::kBgr8, PixelFormat::kMono8,
                        PixelFormat::kBayerRG8},
            .min_exposure_s = 1e-5,
            .max_exposure_s = 2.0,
            .line_trigger = true,
            .readout_s = world_->scene().camera_readout_s,
            .download_s = world_->scene().camera_download_s};
  }

 protected:
  Status DoConfigure(const CaptureSettings& s) override {
    const auto caps = capabilities();
    HR_RETURN_IF_ERROR(CheckExposure(*this, caps, s.exposure_s));
    if (s.format == PixelFormat::kEncoded)
      return OutOfRange(Describe() + ": delivers raw frames only");
    if (s.trigger == TriggerSource::kLine && s.trigger_line.empty()) {
      return InvalidArgument(Describe() + ": line trigger needs a trigger_line");
    }
    settings_ = s;
    return Status::Ok();
  }
  // A camera that dropped off the bus stays absent for the configured number
  // of Open() attempts (fault camera_gone), like a DSLR that re-enumerates.
  Status DoOpen() override {
    if (gone_) {
      if (open_failures_left_ > 0) {
        --open_failures_left_;
        return Unavailable(Describe() +
                           ": not found on the bus (is it connected and switched on?)");
      }
      gone_ = false;
    }
    StopWorker();
    return SimDevice::DoOpen();
  }
  Status DoHealthCheck() override {
    if (gone_) return Fault(Unavailable("not found on the bus"));
    return SimDevice::DoHealthCheck();
  }
  Status DoArm() override {
    StopWorker();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sequence_ = 0;
      ready_.clear();
      stopping_ = false;
    }
    worker_ = std::thread([this] { WorkerLoop(); });
    if (settings_.trigger == TriggerSource::kLine) {
      subscribed_line_ = settings_.trigger_line;
      subscription_ = world_->triggers().Subscribe(subscribed_line_, [this] { OnTrigger(); });
    }
    return Status::Ok();
  }
  Status DoDisarm() override {
    StopWorker();
    return Status::Ok();
  }
  Status DoSoftwareTrigger() override {
    if (gone_) return Fault(Unavailable("dropped off the bus; reopen it"));
    OnTrigger();
    return Status::Ok();
  }
  // The world's trigger bus hands this camera each pulse with its exact time.
  void DoLineTriggerSent(int64_t) override {}
  Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) override {
    if (gone_) return Fault(Unavailable("dropped off the bus; reopen it"));
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_for(lock, timeout, [this] { return !ready_.empty() || gone_; })) {
      return Timeout(Describe() + ": no frame within " + std::to_string(timeout.count()) + " ms");
    }
    if (gone_) return Fault(Unavailable("dropped off the bus; reopen it"));
    Result<Frame> frame = std::move(ready_.front());
    ready_.pop_front();
    return frame;
  }
  Status DoClose() override {
    StopWorker();
    return SimDevice::DoClose();
  }

 private:
  struct Job {
    uint64_t sequence;
    WorldExposure exposure;
    CaptureSettings settings;
    double extra_delay_s = 0;  // download_timeout fault, device seconds
  };

  void OnTrigger() {
    if (gone_) return;
    // The exposure sees the world as it is now; rendering and transfer come after.
    Job job{0, ExposeWorldNow(*world_), settings_};
    const SimFault* fault = NextCameraFault(*world_, info().serial);
    std::lock_guard<std::mutex> lock(mutex_);
    job.sequence = sequence_++;
    if (fault && fault->kind == SimFaultKind::kDropFrame) return;
    if (fault && fault->kind == SimFaultKind::kCameraGone) {
      gone_ = true;
      open_failures_left_ = fault->count;
      SetState(DeviceState::kFaulted);
      cv_.notify_all();
      return;
    }
    if (fault) job.extra_delay_s = fault->delay_s;
    jobs_.push_back(std::move(job));
    cv_.notify_all();
  }

  // A late frame (download_timeout fault) is held aside until it is due, so
  // that it does not hold up the frames behind it.
  void DeliverDueLateFramesLocked() {
    const auto now = Clock::now();
    for (auto it = late_.begin(); it != late_.end();) {
      if (it->first > now) {
        ++it;
        continue;
      }
      if (it->second.ok()) it->second->received_time_ns = SteadyNowNs();
      ready_.push_back(std::move(it->second));
      it = late_.erase(it);
      cv_.notify_all();
    }
  }

  void WorkerLoop() {
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
          DeliverDueLateFramesLocked();
          if (stopping_ || !jobs_.empty()) break;
          auto wake = Clock::time_point::max();
          for (const auto& [due, frame] : late_) wake = std::min(wake, due);
          if (wake == Clock::time_point::max())
            cv_.wait(lock);
          else
            cv_.wait_until(lock, wake);
        }
        if (stopping_) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      const auto t0 = Clock::now();
      Result<Frame> frame = RenderFrame(job);
      // Exposure, readout and download take at least their simulated time.
      const Scene& scene = world_->scene();
      const double minimum_s = (job.settings.exposure_s + scene.camera_readout_s +
                                scene.camera_download_s + job.extra_delay_s) *
                               world_->time_scale();
      const auto due = t0 + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(minimum_s));
      std::unique_lock<std::mutex> lock(mutex_);
      if (job.extra_delay_s > 0) {
        late_.emplace_back(due, std::move(frame));
        continue;
      }
      if (cv_.wait_until(lock, due, [this] { return stopping_; })) {
        return;
      }
      if (frame.ok()) frame->received_time_ns = SteadyNowNs();
      ready_.push_back(std::move(frame));
      cv_.notify_all();
    }
  }

  Result<Frame> RenderFrame(const Job& job) const {
    HR_ASSIGN_OR_RETURN(cv::Mat image,
                        RenderWorldExposure(*world_, scene_camera_, job.exposure,
                                            job.settings.exposure_s, job.settings.gain_db,
                                            FrameNoiseSeed(*world_, info().serial, job.sequence)));
    cv::Mat out;
    switch (job.settings.format) {
      case PixelFormat::kBgr8:
        out = image;
        break;
      case PixelFormat::kRgb8:
        cv::cvtColor(image, out, cv::COLOR_BGR2RGB);
        break;
      case PixelFormat::kMono8:
        cv::cvtColor(image, out, cv::COLOR_BGR2GRAY);
        break;
      case PixelFormat::kBayerRG8:
        out = MosaicRGGB(image);
        break;
      case PixelFormat::kEncoded:
        return Internal("encoded output is not simulated");
    }
    Frame f;
    f.camera_serial = info().serial;
    f.sequence = job.sequence;
    f.width_px = out.cols;
    f.height_px = out.rows;
    f.format = job.settings.format;
    f.data.assign(out.datastart, out.dataend);
    f.exposure_s = job.settings.exposure_s;
    f.gain_db = job.settings.gain_db;
    f.trigger_time_ns = job.exposure.trigger_ns;
    return f;
  }

  void StopWorker() {
    if (subscription_ != 0) {
      world_->triggers().Unsubscribe(subscribed_line_, subscription_);
      subscription_ = 0;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      cv_.notify_all();
    }
    if (worker_.joinable()) worker_.join();
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.clear();
    late_.clear();
  }

  int scene_camera_;
  std::string configured_line_;
  CaptureSettings settings_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  std::deque<Result<Frame>> ready_;
  std::vector<std::pair<Clock::time_point, Result<Frame>>> late_;
  uint64_t sequence_ = 0;
  bool stopping_ = false;
  std::thread worker_;
  std::string subscribed_line_;
  int subscription_ = 0;
  std::atomic<bool> gone_{false};
  int open_failures_left_ = 0;
};

// A sim device with no fields of its own beyond name, backend and serial.
template <typename Interface, typename Impl>
void RegisterFieldlessSimBackend(DeviceRegistry* registry, DeviceKind kind,
                                 const std::string& model, std::shared_ptr<SimWorld> world) {
  registry->AddBackend<Interface>(
      kind, "sim", [world, model](const DeviceConfig& c) -> Result<std::unique_ptr<Interface>> {
        c.node.AllowOnlyKeys({"name", "backend", "serial"});
        if (!c.node.ok()) return c.node.status();
        return std::unique_ptr<Interface>(std::make_unique<Impl>(c.Info(model), world));
      });
}

}  // namespace

void RegisterSimBackends(DeviceRegistry* registry, std::shared_ptr<SimWorld> world) {
  RegisterFieldlessSimBackend<Turntable, SimTurntable>(registry, DeviceKind::kTurntable,
                                                       "simulated turntable", world);
  registry->AddBackend<Light>(
      DeviceKind::kLight, "sim", [world](const DeviceConfig& c) -> Result<std::unique_ptr<Light>> {
        c.node.AllowOnlyKeys({"name", "backend", "serial", "light"});
        const std::string scene_light = c.node.String("light", c.name);
        if (!c.node.ok()) return c.node.status();
        bool known = false;
        for (const SceneLight& l : world->scene().lights) known = known || l.name == scene_light;
        if (!known)
          return NotFound("the simulated scene has no light '" + scene_light +
                          "' (set 'light:' to a scene light)");
        return std::unique_ptr<Light>(
            std::make_unique<SimLight>(c.Info("simulated LED panel"), world, scene_light));
      });
  RegisterFieldlessSimBackend<TriggerLine, SimTriggerLine>(registry, DeviceKind::kTriggerLine,
                                                           "simulated trigger line", world);
  RegisterFieldlessSimBackend<InputLine, SimInputLine>(registry, DeviceKind::kInputLine,
                                                       "simulated e-stop input", world);
  registry->AddBackend<Camera>(
      DeviceKind::kCamera, "sim",
      [world](const DeviceConfig& c) -> Result<std::unique_ptr<Camera>> {
        c.node.AllowOnlyKeys({"name", "backend", "serial", "trigger_line"});
        const std::string line = c.node.String("trigger_line", "");
        if (!c.node.ok()) return c.node.status();
        const int index = world->scene().FindCamera(c.serial);
        if (index < 0) {
          return NotFound("the simulated scene (" + world->scene().path +
                          ") has no camera with serial '" + c.serial + "'");
        }
        return std::unique_ptr<Camera>(
            std::make_unique<SimCamera>(c.Info("simulated camera"), world, index, line));
      });
}

}  // namespace hairrig
