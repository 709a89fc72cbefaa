#include "drivers/device.h"

namespace hairrig {

const char* DeviceKindName(DeviceKind kind) {
  switch (kind) {
    case DeviceKind::kTurntable:
      return "turntable";
    case DeviceKind::kLight:
      return "light";
    case DeviceKind::kCamera:
      return "camera";
    case DeviceKind::kTriggerLine:
      return "trigger line";
    case DeviceKind::kInputLine:
      return "input line";
  }
  return "device";
}

const char* DeviceStateName(DeviceState state) {
  switch (state) {
    case DeviceState::kClosed:
      return "closed";
    case DeviceState::kReady:
      return "ready";
    case DeviceState::kBusy:
      return "busy";
    case DeviceState::kFaulted:
      return "faulted";
  }
  return "?";
}

std::string Device::Describe() const {
  return std::string(DeviceKindName(info_.kind)) + " '" + info_.name + "' (" + info_.backend +
         ", serial " + info_.serial + ")";
}

Status Device::RequireState(std::initializer_list<DeviceState> allowed, const char* call) const {
  const DeviceState now = state();
  std::string names;
  for (DeviceState s : allowed) {
    if (s == now) return Status::Ok();
    names += (names.empty() ? "" : " or ") + std::string(DeviceStateName(s));
  }
  std::string hint = now == DeviceState::kClosed    ? " (call Open first)"
                     : now == DeviceState::kFaulted ? " (Close and Open it again to recover)"
                                                    : "";
  return FailedPrecondition(Describe() + ": " + call + " needs state " + names + " but it is " +
                            DeviceStateName(now) + hint);
}

Status Device::Open() { return DoOpen(); }

Status Device::Close() {
  const Status s = DoClose();
  SetState(DeviceState::kClosed);
  return s;
}

Status Device::HealthCheck() {
  HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady, DeviceState::kBusy}, "HealthCheck"));
  return DoHealthCheck();
}

Status Device::Fault(const Status& status) {
  SetState(DeviceState::kFaulted);
  return status.WithContext(Describe());
}

}  // namespace hairrig
