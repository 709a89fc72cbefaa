// A digital input (GPIO line, or simulated): an e-stop button or a door
// interlock. The capture and the console treat every configured input line as
// a safety input: while it is active, motion stops and the panels are switched
// off. A safety input that cannot be read counts as active (fail-safe): a
// backend whose line faults says so once through the OnChange callback, with
// `true`, after marking the device faulted.
//
// States (drivers/device.h; each call checks its row, then calls its Do hook):
//   call       allowed in   transition
//   IsActive   ready        -
//   OnChange   any state    -
#pragma once

#include <functional>
#include <string>

#include "drivers/device.h"

namespace hairrig {

class InputLine : public Device {
 public:
  using Device::Device;
  // Level now (true = active, i.e. stop requested).
  Result<bool> IsActive();
  // Called on every edge, from a driver thread, with the new level, and with
  // `true` when the line faults (state() is then faulted). One callback per
  // line; an empty function removes it. The callback must be quick and must
  // not call back into this device.
  void OnChange(std::function<void(bool active)> callback);

 protected:
  // The backend's side of the calls above, called once the state allows the call.
  virtual Result<bool> DoIsActive() = 0;
  virtual void DoOnChange(std::function<void(bool active)> callback) = 0;
};

// What a safety input's stop says: "<line> went active (e-stop or interlock)",
// or for a faulted line "<line> cannot be read (...counts as pressed)".
inline std::string DescribeSafetyStop(const InputLine& line) {
  return line.state() == DeviceState::kFaulted
             ? line.Describe() +
                   " cannot be read (a safety input that cannot be read counts as "
                   "pressed): check its wiring and reconnect it"
             : line.Describe() + " went active (e-stop or interlock)";
}

}  // namespace hairrig
