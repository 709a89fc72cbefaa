#include "sim_hw/sim_devices.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "drivers/always_present_device.h"
#include "drivers/camera_support.h"
#include "drivers/polled_turntable.h"
#include "drivers/trigger_bus.h"
#include "sim_hw/sim_turntable_controller.h"
#include "sim_hw/sim_world_model.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

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
