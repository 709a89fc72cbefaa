#include "drivers/gpio_devices.h"

#include <atomic>
#include <mutex>
#include <thread>

namespace hairrig {

namespace {

// Close/HealthCheck of a device holding one requested line, and the request of Open.
template <typename Base, typename Line>
class GpioDevice : public Base {
 public:
  GpioDevice(const DeviceInfo& info, std::shared_ptr<GpioProvider> provider,
             GpioLineRequest request)
      : Base(info), provider_(std::move(provider)), request_(std::move(request)) {}

 protected:
  Status DoClose() override {
    line_.reset();
    return Status::Ok();
  }
  Status DoHealthCheck() override {
    return line_ ? Status::Ok() : Internal(this->Describe() + ": ready without a line");
  }
  // Requests the line through `request` (a provider call) and marks the device ready.
  template <typename RequestFn>
  Status OpenWith(RequestFn request) {
    line_.reset();
    auto line = request(*provider_, request_);
    if (!line.ok()) return this->Fault(line.status());
    line_ = std::move(line).value();
    this->SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status Checked(const Status& s) {
    return s.ok() ? s : this->Fault(s.WithContext(request_.Describe()));
  }

  std::shared_ptr<GpioProvider> provider_;
  GpioLineRequest request_;
  std::unique_ptr<Line> line_;
};

Result<std::unique_ptr<GpioOutputLine>> RequestOutput(GpioProvider& p, const GpioLineRequest& r) {
  return p.RequestOutput(r);
}

class GpioLight : public GpioDevice<Light, GpioOutputLine> {
 public:
  using GpioDevice::GpioDevice;
  ~GpioLight() override { (void)GpioLight::DoClose(); }
  LightCapabilities capabilities() const override { return {.dimmable = false}; }

 protected:
  Status DoOpen() override { return OpenWith(RequestOutput); }
  Status DoClose() override {
    if (line_ && on_) (void)line_->Set(false);  // panels off when the program lets go
    on_ = false;
    return GpioDevice::DoClose();
  }
  Status DoSetOn(bool on) override {
    HR_RETURN_IF_ERROR(Checked(line_->Set(on)));
    on_ = on;
    return Status::Ok();
  }
  Status DoSetLevel(double level) override {
    HR_ASSIGN_OR_RETURN(const bool on, OnOffFromLevel(*this, level, "a GPIO-switched panel"));
    return DoSetOn(on);
  }
  Result<bool> DoIsOn() override { return on_; }

 private:
  bool on_ = false;
};

class GpioTrigger : public GpioDevice<TriggerLine, GpioOutputLine> {
 public:
  using GpioDevice::GpioDevice;

 protected:
  Status DoOpen() override { return OpenWith(RequestOutput); }
  Status DoPulse(std::chrono::microseconds width) override {
    if (width.count() <= 0) return InvalidArgument(Describe() + ": pulse width must be positive");
    HR_RETURN_IF_ERROR(Checked(line_->Set(true)));
    std::this_thread::sleep_for(width);
    return Checked(line_->Set(false));
  }
  Status DoSet(bool active) override { return Checked(line_->Set(active)); }
};

class GpioInput : public GpioDevice<InputLine, GpioInputLine> {
 public:
  using GpioDevice::GpioDevice;
  ~GpioInput() override { StopWatcher(); }

 protected:
  // The line is ready before the watcher starts: a fault the watcher finds stays.
  Status DoOpen() override {
    StopWatcher();
    HR_RETURN_IF_ERROR(
        OpenWith([](GpioProvider& p, const GpioLineRequest& r) { return p.RequestInput(r); }));
    stop_ = false;
    watcher_ = std::thread([this] { Watch(); });
    return Status::Ok();
  }
  Status DoClose() override {
    StopWatcher();
    return GpioDevice::DoClose();
  }
  Result<bool> DoIsActive() override {
    auto level = line_->Get();
    if (!level.ok()) return Checked(level.status());
    return level.value();
  }
  void DoOnChange(std::function<void(bool active)> callback) override {
    std::lock_guard<std::mutex> lock(callback_mutex_);
    callback_ = std::move(callback);
  }

 private:
  void StopWatcher() {
    stop_ = true;
    if (watcher_.joinable()) watcher_.join();
  }
  // Delivers every edge to the callback until stopped. An I/O failure faults
  // the device, tells the callback `true` (a safety input that cannot be read
  // counts as pressed: drivers/input_line.h) and ends the watch.
  void Watch() {
    while (!stop_) {
      auto edge = line_->WaitEdge(std::chrono::milliseconds(50));
      if (!edge.ok()) {
        (void)Checked(edge.status());
        std::lock_guard<std::mutex> lock(callback_mutex_);
        if (callback_) callback_(true);
        return;
      }
      if (!edge.value()) continue;
      std::lock_guard<std::mutex> lock(callback_mutex_);
      if (callback_) callback_(edge.value()->became_active);
    }
  }

  std::atomic<bool> stop_{true};
  std::thread watcher_;
  std::mutex callback_mutex_;
  std::function<void(bool)> callback_;
};

Result<GpioLineRequest> ParseLineRequest(const DeviceConfig& c, bool input) {
  const ConfigNode& n = c.node;
  if (input) {
    n.AllowOnlyKeys({"name", "backend", "serial", "chip", "line", "active_low", "bias"});
  } else {
    n.AllowOnlyKeys({"name", "backend", "serial", "chip", "line", "active_low"});
  }
  GpioLineRequest r;
  r.chip = n.String("chip");
  r.offset = n.Integer("line", {.min = 0, .max = 4095});
  r.consumer = "hairrig " + c.name;
  r.active_low = n.Bool("active_low", false);
  const std::string bias = n.Choice("bias", {"as_is", "disable", "pull_up", "pull_down"}, "as_is");
  r.bias = bias == "disable"     ? GpioBias::kDisable
           : bias == "pull_up"   ? GpioBias::kPullUp
           : bias == "pull_down" ? GpioBias::kPullDown
                                 : GpioBias::kAsIs;
  if (!n.ok()) return n.status();
  return r;
}

template <typename Interface, typename Impl>
void AddGpioBackend(DeviceRegistry* registry, DeviceKind kind, const char* model, bool input,
                    std::shared_ptr<GpioProvider> provider) {
  registry->AddBackend<Interface>(
      kind, "gpiod",
      [provider, model, input](const DeviceConfig& c) -> Result<std::unique_ptr<Interface>> {
        HR_ASSIGN_OR_RETURN(GpioLineRequest request, ParseLineRequest(c, input));
        const DeviceInfo info =
            c.Info(std::string(model) + " (" + request.Describe() + ", " + provider->name() + ")");
        return std::unique_ptr<Interface>(
            std::make_unique<Impl>(info, provider, std::move(request)));
      });
}

}  // namespace

void RegisterGpioBackends(DeviceRegistry* registry, std::shared_ptr<GpioProvider> provider) {
  AddGpioBackend<Light, GpioLight>(registry, DeviceKind::kLight, "GPIO-switched panel", false,
                                   provider);
  AddGpioBackend<TriggerLine, GpioTrigger>(registry, DeviceKind::kTriggerLine,
                                           "GPIO trigger output", false, provider);
  AddGpioBackend<InputLine, GpioInput>(registry, DeviceKind::kInputLine, "GPIO safety input", true,
                                       provider);
}

}  // namespace hairrig
