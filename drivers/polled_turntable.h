// The part every turntable driver that polls its controller shares: the
// target and stop bookkeeping of a move, and the wait that polls the status
// until the platform is in position, the controller reports a fault, the
// move is stopped from another thread (an e-stop), or time runs out.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "drivers/turntable.h"

namespace hairrig {

// One poll of a controller while a move runs.
struct MotionPoll {
  double position_deg = 0;
  bool done = false;                 // in position (and homed, when waiting for a homing)
  std::optional<std::string> fault;  // the controller's fault, in words ("fault code 1 (...)")
};

class PolledTurntable : public Turntable {
 public:
  using Turntable::Turntable;

 protected:
  // Records a commanded move (or homing) to `target_deg`: the device is busy.
  void MoveStarted(double target_deg);
  // Records a stop request: a running wait returns Unavailable at its next poll.
  // (Turntable::Stop marks a busy device ready once DoStop succeeds.)
  void StopRequested();
  // Calls `poll` every `period` until done (ready), a fault (faulted,
  // DeviceFault), a stop (Unavailable) or `timeout` (Timeout). A failing
  // poll's status is returned as it is.
  Status WaitUntilDone(std::chrono::milliseconds timeout, std::chrono::milliseconds period,
                       const std::function<Result<MotionPoll>()>& poll);
  double target_deg() const { return target_deg_; }

 private:
  double target_deg_ = 0;
  std::atomic<bool> stopped_{false};
};

}  // namespace hairrig
