// A digital input (GPIO line, or simulated): an e-stop button or a door
// interlock. The capture treats every configured input line as a safety input:
// while it is active, motion stops and the panels are switched off.
#pragma once

#include <functional>

#include "drivers/device.h"

namespace hairrig {

class InputLine : public Device {
 public:
  using Device::Device;
  // Level now (true = active, i.e. stop requested).
  virtual Result<bool> IsActive() = 0;
  // Called on every edge, from a driver thread, with the new level. One
  // callback per line; an empty function removes it. The callback must be
  // quick and must not call back into this device.
  virtual void OnChange(std::function<void(bool active)> callback) = 0;
};

}  // namespace hairrig
