// The calibration input a capture of a simulated scene starts from: its box,
// the box height and its cameras (no nominal intrinsics), without frames.
// Shared by tests/calibration_uncertainty_test.cpp and bench/calibration_bench.cpp.
#pragma once

#include "calibration/capture_calibration.h"
#include "sim_hw/scene.h"

namespace hairrig_test {

inline hairrig::CaptureCalibrationInput SceneCalibrationInput(const hairrig::Scene& scene) {
  hairrig::CaptureCalibrationInput input;
  input.box = scene.box;
  input.box_height_mm = scene.turntable_from_box.translation.z();
  for (const hairrig::SceneCamera& camera : scene.cameras) {
    hairrig::CalibrationCamera c;
    c.name = c.serial = camera.serial;
    c.width_px = camera.intrinsics.width_px;
    c.height_px = camera.intrinsics.height_px;
    input.cameras.push_back(c);
  }
  return input;
}

}  // namespace hairrig_test
