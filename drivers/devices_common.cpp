#include <cmath>
#include <cstdio>
#include <thread>

#include "core/config.h"
#include "drivers/camera.h"
#include "drivers/camera_support.h"
#include "drivers/input_line.h"
#include "drivers/light.h"
#include "drivers/polled_turntable.h"
#include "drivers/trigger_line.h"
#include "drivers/turntable.h"

namespace hairrig {

Result<bool> OnOffFromLevel(const Light& light, double level, const std::string& what) {
  if (level == 0.0 || level == 1.0) return level == 1.0;
  if (level >= 0 && level <= 1) {
    return FailedPrecondition(light.Describe() + ": " + what +
                              " is on or off; level must be 0 or 1");
  }
  return OutOfRange(light.Describe() + ": level must be within 0..1");
}

CameraNominal ReadCameraNominal(const ConfigNode& device, const CameraNominal& defaults) {
  CameraNominal n = defaults;
  n.width_px = device.Integer("width_px", defaults.width_px, {.min = 0, .max = 100000});
  n.height_px = device.Integer("height_px", defaults.height_px, {.min = 0, .max = 100000});
  n.readout_s = device.Number("readout_s", defaults.readout_s, {.min = 0, .max = 60});
  n.download_s = device.Number("download_s", defaults.download_s, {.min = 0, .max = 600});
  return n;
}

Status CameraNominal::Check() const {
  if (width_px < 0 || width_px > 100000)
    return InvalidArgument("width_px must lie in 0..100000, got " + std::to_string(width_px));
  if (height_px < 0 || height_px > 100000)
    return InvalidArgument("height_px must lie in 0..100000, got " + std::to_string(height_px));
  if (!(readout_s >= 0 && readout_s <= 60))
    return InvalidArgument("readout_s must lie in [0, 60] s, got " + std::to_string(readout_s));
  if (!(download_s >= 0 && download_s <= 600))
    return InvalidArgument("download_s must lie in [0, 600] s, got " + std::to_string(download_s));
  if (!(time_scale > 0) || !std::isfinite(time_scale))
    return InvalidArgument("time_scale must be finite and positive");
  return Status::Ok();
}

Status CheckExposure(const Camera& camera, const CameraCapabilities& caps, double exposure_s) {
  if (exposure_s >= caps.min_exposure_s && exposure_s <= caps.max_exposure_s) return Status::Ok();
  return OutOfRange(camera.Describe() + ": exposure_s " + std::to_string(exposure_s) +
                    " outside the camera's " + std::to_string(caps.min_exposure_s) + " - " +
                    std::to_string(caps.max_exposure_s) + " s");
}

// --- the state tables of drivers/turntable.h, light.h, camera.h, trigger_line.h, input_line.h

Status Turntable::Home(std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady, DeviceState::kBusy}, "Home"));
  return DoHome(timeout);
}

Status Turntable::StartMove(double target_deg, const MotionProfile& profile) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady, DeviceState::kBusy}, "StartMove"));
  return DoStartMove(target_deg, profile);
}

Result<TurntableStatus> Turntable::ReadStatus() {
  HR_RETURN_IF_ERROR(
      RequireState({DeviceState::kReady, DeviceState::kBusy, DeviceState::kFaulted}, "ReadStatus"));
  return DoReadStatus();
}

Status Turntable::WaitInPosition(std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady, DeviceState::kBusy}, "WaitInPosition"));
  return DoWaitInPosition(timeout);
}

Status Turntable::Stop() {
  HR_RETURN_IF_ERROR(
      RequireState({DeviceState::kReady, DeviceState::kBusy, DeviceState::kFaulted}, "Stop"));
  HR_RETURN_IF_ERROR(DoStop());
  if (state() == DeviceState::kBusy) SetState(DeviceState::kReady);
  return Status::Ok();
}

Status Turntable::MoveTo(double target_deg, const MotionProfile& profile,
                         std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(StartMove(target_deg, profile));
  return WaitInPosition(timeout);
}

Status Light::SetOn(bool on) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "SetOn"));
  return DoSetOn(on);
}

Status Light::SetLevel(double level) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "SetLevel"));
  return DoSetLevel(level);
}

Result<bool> Light::IsOn() {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "IsOn"));
  return DoIsOn();
}

Status Camera::Configure(const CaptureSettings& settings) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Configure"));
  return DoConfigure(settings);
}

Status Camera::Arm() {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Arm"));
  HR_RETURN_IF_ERROR(DoArm());
  SetState(DeviceState::kBusy);
  return Status::Ok();
}

Status Camera::Disarm() {
  HR_RETURN_IF_ERROR(DoDisarm());
  if (state() == DeviceState::kBusy) SetState(DeviceState::kReady);
  return Status::Ok();
}

Status Camera::SoftwareTrigger() {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kBusy}, "SoftwareTrigger (after Arm)"));
  return DoSoftwareTrigger();
}

void Camera::LineTriggerSent(int64_t sent_ns) { DoLineTriggerSent(sent_ns); }

Result<Frame> Camera::WaitFrame(std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kBusy}, "WaitFrame (after Arm)"));
  return DoWaitFrame(timeout);
}

Result<Frame> Camera::CapturePreview(std::chrono::milliseconds timeout) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "CapturePreview"));
  return DoCapturePreview(timeout);
}

Status TriggerLine::Pulse(std::chrono::microseconds width) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Pulse"));
  return DoPulse(width);
}

Status TriggerLine::Set(bool active) {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Set"));
  return DoSet(active);
}

Result<bool> InputLine::IsActive() {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "IsActive"));
  return DoIsActive();
}

void InputLine::OnChange(std::function<void(bool active)> callback) {
  DoOnChange(std::move(callback));
}

Status CheckMoveRequest(const std::string& device, double target_deg, const MotionProfile& p,
                        const TurntableCapabilities& caps) {
  if (!std::isfinite(target_deg))
    return InvalidArgument(device + ": target angle is not a finite number");
  if (!(p.speed_deg_s > 0 && p.speed_deg_s <= caps.max_speed_deg_s)) {
    return OutOfRange(device + ": speed " + std::to_string(p.speed_deg_s) + " deg/s outside (0, " +
                      std::to_string(caps.max_speed_deg_s) + "]");
  }
  if (!(p.accel_deg_s2 > 0 && p.accel_deg_s2 <= caps.max_accel_deg_s2)) {
    return OutOfRange(device + ": acceleration " + std::to_string(p.accel_deg_s2) +
                      " deg/s^2 outside (0, " + std::to_string(caps.max_accel_deg_s2) + "]");
  }
  return Status::Ok();
}

std::string DegreesText(double deg) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f deg", deg);
  return text;
}

void PolledTurntable::MoveStarted(double target_deg) {
  target_deg_ = target_deg;
  stopped_ = false;
  SetState(DeviceState::kBusy);
}

void PolledTurntable::StopRequested() { stopped_ = true; }

Status PolledTurntable::WaitUntilDone(std::chrono::milliseconds timeout,
                                      std::chrono::milliseconds period,
                                      const std::function<Result<MotionPoll>()>& poll) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (stopped_)
      return Unavailable(Describe() + ": the move was stopped before reaching " +
                         DegreesText(target_deg_));
    HR_ASSIGN_OR_RETURN(const MotionPoll p, poll());
    if (p.fault) {
      return Fault(DeviceFault("the controller reports " + *p.fault + " at " +
                               DegreesText(p.position_deg) + " on the way to " +
                               DegreesText(target_deg_) +
                               ": check that nothing blocks the platform, then home it again"));
    }
    if (p.done) break;
    if (Clock::now() >= deadline) {
      return Timeout(Describe() + ": not in position at " + DegreesText(target_deg_) + " within " +
                     std::to_string(timeout.count()) + " ms (now at " +
                     DegreesText(p.position_deg) + ")");
    }
    std::this_thread::sleep_for(std::min<Clock::duration>(deadline - Clock::now(), period));
  }
  SetState(DeviceState::kReady);
  return Status::Ok();
}

double MoveDurationS(double distance_deg, const MotionProfile& profile) {
  const double d = std::abs(distance_deg);
  const double t_acc = profile.speed_deg_s / profile.accel_deg_s2;
  if (d < profile.speed_deg_s * t_acc) return 2 * std::sqrt(d / profile.accel_deg_s2);
  return d / profile.speed_deg_s + t_acc;
}

const char* PixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return "Mono8";
    case PixelFormat::kRgb8:
      return "RGB8";
    case PixelFormat::kBgr8:
      return "BGR8";
    case PixelFormat::kBayerRG8:
      return "BayerRG8";
    case PixelFormat::kEncoded:
      return "Encoded";
  }
  return "?";
}

int BytesPerPixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
    case PixelFormat::kBayerRG8:
      return 1;
    case PixelFormat::kRgb8:
    case PixelFormat::kBgr8:
      return 3;
    case PixelFormat::kEncoded:
      return 0;
  }
  return 0;
}

size_t Frame::ExpectedBytes() const {
  return static_cast<size_t>(width_px) * static_cast<size_t>(height_px) *
         static_cast<size_t>(BytesPerPixel(format));
}

}  // namespace hairrig
