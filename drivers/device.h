// The device vocabulary shared by every backend (real, simulated, replay).
//
// Every device has an explicit state and calls that return a Status with a
// message a technician can act on; none aborts or throws on I/O failure.
//
//   closed --Open()--> ready --(start of work)--> busy --(done)--> ready
//      ^                 |  any I/O fault --> faulted --Close()/Open()--> ...
//      +----Close()------+
//
// A call made in the wrong state returns FailedPrecondition naming the device,
// the call and the state. Devices are identified by serial number, never by
// port or bus order; `name` is the role the rig config gives it ("upper").
//
// The states are enforced here and in the interfaces of drivers/, once for
// every backend: each call of an interface is public and non-virtual; it
// checks the state against the interface's table (RequireState), and only
// when the state allows it calls the backend's protected hook of the same name
// with a `Do` prefix (Open -> DoOpen). The call makes the transitions every
// backend shares; the hook makes the others (and marks the device faulted on
// an I/O failure, through Fault). A backend overrides the hooks and checks no
// state of this table itself. Queries (info, state, capabilities, time_scale)
// answer in any state.
//
// Every device:
//   call          allowed in    transition
//   Open          any state     -> ready, made by DoOpen (a reopen reconnects)
//   Close         any state     -> closed, whatever DoClose returns
//   HealthCheck   ready, busy   -
// DoOpen marks the device ready itself, before it starts anything that can
// fault the device (a gpiod input line's edge watcher), so that such a fault
// is never overwritten.
#pragma once

#include <atomic>
#include <initializer_list>
#include <string>

#include "core/status.h"

namespace hairrig {

enum class DeviceKind { kTurntable, kLight, kCamera, kTriggerLine, kInputLine };
enum class DeviceState { kClosed, kReady, kBusy, kFaulted };

const char* DeviceKindName(DeviceKind kind);
const char* DeviceStateName(DeviceState state);

struct DeviceInfo {
  DeviceKind kind = DeviceKind::kCamera;
  std::string name;     // role in the rig config
  std::string backend;  // "sim", "modbus", "gphoto2", ...
  std::string serial;   // identity of the physical unit
  std::string model;    // vendor/model text for humans
};

class Device {
 public:
  explicit Device(DeviceInfo info) : info_(std::move(info)) {}
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const DeviceInfo& info() const { return info_; }
  DeviceState state() const { return state_.load(); }
  // "camera 'upper' (sim, serial SIM-CAM-UPPER)": how messages name the device.
  std::string Describe() const;

  // Finds the unit by serial and connects; Unavailable if absent. -> ready.
  Status Open();
  // Releases the unit. -> closed. Safe to call twice.
  Status Close();
  // Talks to the unit (reads a status register, a config value) without side effects.
  Status HealthCheck();
  // Wall-clock seconds per device second: 1 for real hardware; a simulated
  // device whose timings are scaled to run faster returns its scale. Timings a
  // device reports (capabilities, exposure) are in device seconds.
  virtual double time_scale() const { return 1.0; }

 protected:
  void SetState(DeviceState s) { state_.store(s); }
  // FailedPrecondition unless the state is one of `allowed`.
  Status RequireState(std::initializer_list<DeviceState> allowed, const char* call) const;
  // Marks the device faulted and returns `status` prefixed with Describe().
  Status Fault(const Status& status);

  // The backend's side of Open, Close and HealthCheck, called once the state allows the call.
  // Connects and marks the device ready; an I/O failure marks it faulted (Fault).
  virtual Status DoOpen() = 0;
  // Releases the unit; Close marks the device closed after it.
  virtual Status DoClose() = 0;
  virtual Status DoHealthCheck() = 0;

 private:
  DeviceInfo info_;
  std::atomic<DeviceState> state_{DeviceState::kClosed};
};

}  // namespace hairrig
