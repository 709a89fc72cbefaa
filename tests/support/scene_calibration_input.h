// The calibration input a capture of a simulated scene starts from: its box,
// the box height and its cameras (no nominal intrinsics), without frames.
// Shared by tests/calibration_uncertainty_test.cpp and bench/calibration_bench.cpp.
#pragma once

#include <cmath>

#include "calibration/capture_calibration.h"
#include "sim_hw/scene.h"

namespace hairrig_test {

// The box's turn about the turntable axis in the scene (deg), as a rig config states it.
inline double SceneBoxYawDeg(const hairrig::Scene& scene) {
  const Eigen::Vector3d box_x = scene.turntable_from_box.rotation * Eigen::Vector3d::UnitX();
  return std::atan2(box_x.y(), box_x.x()) * 180 / M_PI;
}

inline hairrig::CaptureCalibrationInput SceneCalibrationInput(const hairrig::Scene& scene) {
  hairrig::CaptureCalibrationInput input;
  input.box = scene.drawn_box;  // what the calibration is given
  input.box_height_mm = scene.turntable_from_box.translation.z();
  input.box_yaw_deg = SceneBoxYawDeg(scene);
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
