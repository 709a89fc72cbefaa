// An LED panel (switched by GPIO or a USB relay board, or simulated).
#pragma once

#include <string>

#include "drivers/device.h"

namespace hairrig {

struct LightCapabilities {
  bool dimmable = false;
};

class Light : public Device {
 public:
  using Device::Device;
  virtual LightCapabilities capabilities() const = 0;
  virtual Status SetOn(bool on) = 0;
  // 0..1; OutOfRange outside it, FailedPrecondition if not dimmable and not 0 or 1.
  virtual Status SetLevel(double level) = 0;
  virtual Result<bool> IsOn() = 0;
};

// The on/off state a level asks of a panel that is only on or off: 0 -> off,
// 1 -> on; FailedPrecondition naming `what` for a level in between,
// OutOfRange outside 0..1.
Result<bool> OnOffFromLevel(const Light& light, double level, const std::string& what);

}  // namespace hairrig
