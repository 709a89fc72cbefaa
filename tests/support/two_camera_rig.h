// A capture's rig.yaml for tests that write a capture's files by hand: the
// simulated rig's two cameras and the calibration box.
#pragma once

namespace hairrig_test {

inline constexpr const char* kTwoCameraRigYaml =
    "name: frames test\ndevices:\n  cameras:\n"
    "    - {name: upper, backend: sim, serial: SIM-CAM-UPPER}\n"
    "    - {name: lower, backend: sim, serial: SIM-CAM-LOWER}\n"
    "calibration:\n  box: calib-box.yaml\n  box_height_mm: 600\n";

}  // namespace hairrig_test
