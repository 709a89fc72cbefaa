// The simulated turntable controller: the motion logic of a stepper/servo
// controller (acceleration-limited moves, homing, in-position flag, stall and
// limit faults) acting on the SimWorld's platform, so that what it does shows
// in the rendered frames.
//
// Two front ends share it: the in-process `sim` turntable (sim_devices.cpp)
// and the Modbus server that simulates a real controller behind its register
// map (sim_hw/modbus_turntable_server.h). The world owns one controller
// (WorldTurntableController in sim_devices.h), whose state, like a real
// controller's, outlives the connections of its clients. Thread-safe.
//
// Angles in degrees (counter-clockwise seen from above), speeds in deg/s and
// accelerations in deg/s^2, all in device time (the world's time_scale maps
// them to wall time).
#pragma once

#include <chrono>
#include <mutex>
#include <optional>

#include "drivers/turntable.h"
#include "sim_hw/sim_faults.h"

namespace hairrig {

class SimWorld;

// The controller's fault code (a Modbus controller's fault register holds it).
enum class TurntableFaultCode : int {
  kNone = 0,
  kStall = 1,  // following error: the platform is blocked
  kLimit = 2,  // a move commanded beyond the speed or acceleration limits
};
const char* TurntableFaultCodeName(TurntableFaultCode code);

struct TurntableControllerStatus {
  double position_deg = 0;
  double target_deg = 0;
  bool moving = false;
  bool in_position = false;
  bool homed = false;
  TurntableFaultCode fault = TurntableFaultCode::kNone;
};

class SimTurntableController {
 public:
  explicit SimTurntableController(SimWorld& world) : world_(world) {}

  TurntableCapabilities capabilities() const;
  // Starts an absolute move. A profile outside the limits is refused: the
  // controller latches a kLimit fault and returns it. The world's turntable
  // faults (timeout, stall, e-stop) are injected here, one event per move.
  TurntableFaultCode StartMove(double target_deg, const MotionProfile& profile);
  // Moves to the index at the homing speed; `homed` is set on arrival.
  void StartHome();
  // Decelerates to a stop at once.
  void Stop();
  // Clears a latched fault (the platform stays where it is).
  void ClearFault();
  // The controller's state now (advances the homing and stall logic).
  TurntableControllerStatus Poll();
  double time_scale() const;

 private:
  // A fault of the safety inputs (estop, input_lost) drawn for a move, which
  // the caller schedules outside the lock (the inputs' handlers may call Stop()).
  struct SafetyEvent {
    SimFaultKind kind = SimFaultKind::kEstop;
    double after_s = 0;  // device seconds into the move
  };
  // Starts the world's motion and draws the move's injected fault.
  std::optional<SafetyEvent> StartMoveLocked(double target_deg, const MotionProfile& profile);

  SimWorld& world_;
  std::mutex mutex_;
  double target_deg_ = 0;
  bool homed_ = false;
  bool homing_ = false;
  TurntableFaultCode fault_ = TurntableFaultCode::kNone;
  double stall_after_s_ = -1;  // device seconds into the move; < 0: no stall
  std::chrono::steady_clock::time_point move_start_ = std::chrono::steady_clock::now();
};

}  // namespace hairrig
