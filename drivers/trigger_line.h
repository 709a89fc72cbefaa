// A digital output that triggers cameras (GPIO line, or simulated). Several
// cameras armed with TriggerSource::kLine on the same line expose together on
// one Pulse().
//
// States (drivers/device.h; each call checks its row, then calls its Do hook):
//   call    allowed in   transition
//   Pulse   ready        -
//   Set     ready        -
#pragma once

#include <chrono>

#include "drivers/device.h"

namespace hairrig {

class TriggerLine : public Device {
 public:
  using Device::Device;
  // Drives the line active for `width`, then inactive. Blocks for the pulse.
  Status Pulse(std::chrono::microseconds width);
  Status Set(bool active);

 protected:
  // The backend's side of the calls above, called once the state allows the call.
  virtual Status DoPulse(std::chrono::microseconds width) = 0;
  virtual Status DoSet(bool active) = 0;
};

}  // namespace hairrig
