#include "sim_hw/sim_turntable_controller.h"

#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>

#include "drivers/turntable.h"
#include "sim_hw/sim_faults.h"
#include "sim_hw/sim_world_model.h"

namespace hairrig {

using Clock = std::chrono::steady_clock;

const char* TurntableFaultCodeName(TurntableFaultCode code) {
  switch (code) {
    case TurntableFaultCode::kNone:
      return "no fault";
    case TurntableFaultCode::kStall:
      return "a stall (following error)";
    case TurntableFaultCode::kLimit:
      return "a move beyond the speed or acceleration limits";
  }
  return "an unknown fault";
}

TurntableCapabilities SimTurntableController::capabilities() const {
  return {.max_speed_deg_s = 90,
          .max_accel_deg_s2 = 360,
          .resolution_deg = 0.001,
          .can_home = true,
          .settle_s = world_.scene().turntable_settle_s};
}

double SimTurntableController::time_scale() const { return world_.time_scale(); }

TurntableFaultCode SimTurntableController::StartMove(double target_deg, const MotionProfile& p) {
  const TurntableCapabilities caps = capabilities();
  std::optional<SafetyEvent> safety_event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!std::isfinite(target_deg) ||
        !(p.speed_deg_s > 0 && p.speed_deg_s <= caps.max_speed_deg_s) ||
        !(p.accel_deg_s2 > 0 && p.accel_deg_s2 <= caps.max_accel_deg_s2)) {
      fault_ = TurntableFaultCode::kLimit;
      return fault_;
    }
    safety_event = StartMoveLocked(target_deg, p);
    homing_ = false;
  }
  // Outside the lock: the inputs' handlers may call Stop().
  if (safety_event) world_.ScheduleSafetyEvent(safety_event->kind, safety_event->after_s);
  return TurntableFaultCode::kNone;
}

void SimTurntableController::StartHome() {
  std::optional<SafetyEvent> safety_event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    safety_event = StartMoveLocked(
        0.0, {world_.scene().turntable_speed_deg_s, world_.scene().turntable_accel_deg_s2});
    homing_ = true;
  }
  if (safety_event) world_.ScheduleSafetyEvent(safety_event->kind, safety_event->after_s);
}

std::optional<SimTurntableController::SafetyEvent> SimTurntableController::StartMoveLocked(
    double target_deg, const MotionProfile& p) {
  const double move_s = MoveDurationS(target_deg - world_.AngleDeg(), p);
  world_.StartMove(target_deg, p);
  target_deg_ = target_deg;
  stall_after_s_ = -1;
  move_start_ = Clock::now();
  const SimFault* fault =
      world_.NextEventFault("", {SimFaultKind::kTurntableTimeout, SimFaultKind::kTurntableStall,
                                 SimFaultKind::kEstop, SimFaultKind::kInputLost});
  if (!fault) return std::nullopt;
  switch (fault->kind) {
    case SimFaultKind::kTurntableTimeout:
      world_.JamMove();
      break;
    case SimFaultKind::kTurntableStall:
      stall_after_s_ = 0.5 * move_s;
      break;
    case SimFaultKind::kEstop:
    case SimFaultKind::kInputLost:
      return SafetyEvent{fault->kind, 0.2 * move_s};
    default:
      break;
  }
  return std::nullopt;
}

void SimTurntableController::Stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  world_.StopMotion();
  homing_ = false;
  stall_after_s_ = -1;
}

void SimTurntableController::ClearFault() {
  std::lock_guard<std::mutex> lock(mutex_);
  fault_ = TurntableFaultCode::kNone;
}

TurntableControllerStatus SimTurntableController::Poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stall_after_s_ >= 0 && world_.SimSecondsSince(move_start_) >= stall_after_s_) {
    world_.StopMotion();
    fault_ = TurntableFaultCode::kStall;
    stall_after_s_ = -1;
    homing_ = false;
  }
  TurntableControllerStatus s;
  s.position_deg = world_.AngleDeg();
  s.target_deg = target_deg_;
  s.fault = fault_;
  const bool ok = fault_ == TurntableFaultCode::kNone;
  // A safety event drawn for the move happens before it ends (SafetyEventPending).
  s.in_position = ok && !world_.SafetyEventPending() && world_.SecondsToInPosition() <= 0;
  s.moving = ok && world_.MotionSecondsLeft() > 0;
  if (homing_ && s.in_position) {
    homed_ = true;
    homing_ = false;
  }
  s.homed = homed_;
  return s;
}

}  // namespace hairrig
