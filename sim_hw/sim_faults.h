// Fault injection for the simulated rig (docs/design.md section 3): the faults a
// real rig meets, switched on from the rig config so that tests can drive the
// capture's error handling through the same device interfaces.
//
//   sim:
//     faults:
//       - {kind: drop_frame, device: SIM-CAM-UPPER, at: 3}        # 3rd trigger's frame never
//       arrives
//       - {kind: camera_gone, device: SIM-CAM-LOWER, at: 5, count: 2}
//                                 # at its 5th trigger the camera drops off the bus; the next 2
//                                 # Open() attempts fail, the one after succeeds
//       - {kind: download_timeout, device: SIM-CAM-UPPER, at: 2, delay_s: 30}
//                                 # the frame arrives delay_s (device seconds) late
//       - {kind: turntable_timeout, at: 4, count: 1}   # the 4th move never reaches position
//       - {kind: turntable_stall, at: 6}               # the 6th move ends in a controller fault
//       - {kind: estop, at: 3}                         # e-stop pressed during the 3rd move
//       - {kind: input_lost, at: 3}    # the safety inputs' wiring breaks during the 3rd move:
//                                 # they cannot be read from then on (a read faults the line)
//       - {kind: disk_full, at: 10}                    # the capture's disk holds 10 frame files:
//                                 # writing the 11th fails with ENOSPC (sim_hw/quota_storage.h)
//
// `at` counts events of the device from 1 (triggers of that camera, moves of
// the turntable) over the life of the simulated world, so a fault fires once
// even when a capture retries. `count` is how many consecutive events it
// affects (default 1). Both are at most 1,000,000, `delay_s` at most 3600.
// A disk_full fault's `at` is the frame files the disk holds, counted over the
// life of the rig built with the fault (BuildRig): a session resumed with the
// same fault stores `at` more frames.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"

namespace hairrig {

enum class SimFaultKind {
  kDropFrame,
  kCameraGone,
  kDownloadTimeout,
  kTurntableTimeout,
  kTurntableStall,
  kEstop,
  kInputLost,
  kDiskFull,
};

struct SimFault {
  SimFaultKind kind = SimFaultKind::kDropFrame;
  std::string device;  // camera serial for camera faults; empty otherwise
  int at = 1;
  int count = 1;
  double delay_s = 30;  // download_timeout only
  // True when the `event`-th event (from 1) of this fault's device is affected.
  // A camera_gone fault happens once; its count is the failed Open() attempts.
  bool Hits(int event) const {
    return kind == SimFaultKind::kCameraGone ? event == at : event >= at && event < at + count;
  }
};

// Reads the `faults` list; errors name the file, line and field.
Result<std::vector<SimFault>> ParseSimFaults(const ConfigNode& faults);
const char* SimFaultKindName(SimFaultKind kind);

}  // namespace hairrig
