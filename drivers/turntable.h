// A motorised turntable (Modbus stepper/servo controller, or simulated).
// Angles in degrees, increasing counter-clockwise seen from above (about world
// +z, core/transform.h). Positions are absolute after Home().
//
// States (drivers/device.h; each call checks its row, then calls its Do hook):
//   call            allowed in              transition
//   Home            ready, busy             the backend's (polled: busy while homing, then ready)
//   StartMove       ready, busy             the backend's: busy once the controller took the move
//   ReadStatus      ready, busy, faulted    the backend's (polled: busy -> ready when in position)
//   WaitInPosition  ready, busy             the backend's: ready when in position
//   Stop            ready, busy, faulted    busy -> ready on success
//   MoveTo          StartMove, then WaitInPosition, each with its own row
// Stop's transition is made by Stop itself; the motion transitions stay with
// the backend, which marks the device busy when the controller has the
// command, so that a Stop() from another thread (an e-stop) that ends the move
// is never overwritten.
#pragma once

#include <chrono>
#include <string>

#include "drivers/device.h"

namespace hairrig {

struct TurntableCapabilities {
  double max_speed_deg_s = 0;
  double max_accel_deg_s2 = 0;
  double resolution_deg = 0;  // smallest commandable step
  bool can_home = true;
  double settle_s = 0;  // time after the in-position flag before the platform is still
};

struct MotionProfile {
  double speed_deg_s = 30;
  double accel_deg_s2 = 60;
};

// Duration (s) of an acceleration-limited (trapezoidal, or triangular when
// short) move of |distance_deg|, from rest to rest.
double MoveDurationS(double distance_deg, const MotionProfile& profile);

struct TurntableStatus {
  double position_deg = 0;  // measured (encoder)
  double target_deg = 0;    // last commanded
  bool moving = false;
  bool in_position = false;  // controller's in-position flag
  bool homed = false;
  bool fault = false;
};

// Ok, or InvalidArgument / OutOfRange naming `device` when the target is not
// finite or the profile is outside `caps` (a driver checks before commanding).
Status CheckMoveRequest(const std::string& device, double target_deg, const MotionProfile& profile,
                        const TurntableCapabilities& caps);
// "12.345 deg", for messages.
std::string DegreesText(double deg);

class Turntable : public Device {
 public:
  using Device::Device;
  virtual TurntableCapabilities capabilities() const = 0;
  // Finds the index and sets position 0. Blocks up to `timeout`.
  Status Home(std::chrono::milliseconds timeout);
  // Starts an absolute move and returns at once (state busy until in position).
  // OutOfRange if the profile exceeds the capabilities.
  Status StartMove(double target_deg, const MotionProfile& profile);
  Result<TurntableStatus> ReadStatus();
  // Blocks until the in-position flag is set; Timeout if not within `timeout`,
  // DeviceFault if the controller reports a fault (stall, following error).
  Status WaitInPosition(std::chrono::milliseconds timeout);
  // Decelerates to a stop at once (e-stop, interlock); valid in any open state.
  Status Stop();

  // StartMove then WaitInPosition.
  Status MoveTo(double target_deg, const MotionProfile& profile, std::chrono::milliseconds timeout);

 protected:
  // The backend's side of the calls above, called once the state allows the call.
  virtual Status DoHome(std::chrono::milliseconds timeout) = 0;
  virtual Status DoStartMove(double target_deg, const MotionProfile& profile) = 0;
  virtual Result<TurntableStatus> DoReadStatus() = 0;
  virtual Status DoWaitInPosition(std::chrono::milliseconds timeout) = 0;
  // Commands the stop; Stop marks a busy device ready after it succeeds.
  virtual Status DoStop() = 0;
};

}  // namespace hairrig
