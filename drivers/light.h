// An LED panel (switched by GPIO or a USB relay board, or simulated).
//
// States (drivers/device.h; each call checks its row, then calls its Do hook):
//   call       allowed in   transition
//   SetOn      ready        -
//   SetLevel   ready        -
//   IsOn       ready        -
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
  Status SetOn(bool on);
  // 0..1; OutOfRange outside it, FailedPrecondition if not dimmable and not 0 or 1.
  Status SetLevel(double level);
  Result<bool> IsOn();

 protected:
  // The backend's side of the calls above, called once the state allows the call.
  virtual Status DoSetOn(bool on) = 0;
  virtual Status DoSetLevel(double level) = 0;
  virtual Result<bool> DoIsOn() = 0;
};

// The on/off state a level asks of a panel that is only on or off: 0 -> off,
// 1 -> on; FailedPrecondition naming `what` for a level in between,
// OutOfRange outside 0..1.
Result<bool> OnOffFromLevel(const Light& light, double level, const std::string& what);

}  // namespace hairrig
