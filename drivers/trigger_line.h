// A digital output that triggers cameras (GPIO line, or simulated). Several
// cameras armed with TriggerSource::kLine on the same line expose together on
// one Pulse().
#pragma once

#include <chrono>

#include "drivers/device.h"

namespace hairrig {

class TriggerLine : public Device {
 public:
  using Device::Device;
  // Drives the line active for `width`, then inactive. Blocks for the pulse.
  virtual Status Pulse(std::chrono::microseconds width) = 0;
  virtual Status Set(bool active) = 0;
};

}  // namespace hairrig
