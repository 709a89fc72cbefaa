// A capture's calibration as `hairrig calibrate` hands it to the exporters
// (calibration/calibration_io.h), made up without rendering or solving: two
// cameras of the default rig's size (the lower one with k3, so COLMAP's
// FULL_OPENCV model), the turntable mode with the box tilted on the plate,
// both cameras at six stops, and one view that failed (exported nowhere but
// calibration.json). For tests that read the exports back with the tools
// they are for. Header-only, for tests.
#pragma once

#include <cstdio>
#include <string>

#include "calibration/capture_calibration.h"
#include "core/transform.h"

namespace hairrig_test {

struct SyntheticCalibration {
  hairrig::CaptureCalibrationInput input;
  hairrig::CaptureCalibration result;
  int failed_view = 5;  // the view whose frame is not solved
};

inline SyntheticCalibration MakeSyntheticCalibration() {
  using hairrig::CameraIntrinsics;
  using hairrig::Rigid3d;
  SyntheticCalibration s;
  const CameraIntrinsics upper{1200,
                               1600,
                               1749.8447835361924,
                               1749.8838493984285,
                               602.59587352542007,
                               795.72770652429108,
                               -0.029986734829417799,
                               0.012930158142127515,
                               0.00024168287194011089,
                               -6.8615811219148489e-05,
                               0};
  const CameraIntrinsics lower{1200,
                               1600,
                               1760.0453227376609,
                               1757.9913994379729,
                               596.05661063779542,
                               803.03574349616838,
                               -0.027771058289044592,
                               0.010606650879411431,
                               -0.00011913172691481111,
                               0.00019900472450612119,
                               0.0021314159265358979};
  const Eigen::Vector3d eyes_mm[2] = {{900, 0, 700}, {900, 0, 200}};
  const Eigen::Vector3d targets_mm[2] = {{0, 0, 390}, {0, 0, 400}};
  s.result.mode = hairrig::CalibrationMode::kTurntable;
  s.result.turntable_from_box = Rigid3d(
      Eigen::Quaterniond(
          Eigen::AngleAxisd(hairrig::DegToRad(10.0), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(hairrig::DegToRad(0.7), Eigen::Vector3d(1, -2, 0).normalized())),
      Eigen::Vector3d(0.31, -0.27, 600.4));
  for (int c = 0; c < 2; ++c) {
    hairrig::CalibrationCamera input_camera;
    input_camera.name = c == 0 ? "upper" : "lower";
    input_camera.serial = c == 0 ? "SIM-CAM-UPPER" : "SIM-CAM-LOWER";
    input_camera.width_px = 1200;
    input_camera.height_px = 1600;
    s.input.cameras.push_back(input_camera);
    hairrig::CameraCalibration camera;
    camera.solved = true;
    camera.intrinsics_source = "views";
    camera.intrinsics = camera.initial = c == 0 ? upper : lower;
    camera.cam_from_world = hairrig::LookAt(eyes_mm[c], targets_mm[c]);
    s.result.cameras.push_back(camera);
  }
  const int stops = 6;
  for (int stop = 0; stop < stops; ++stop) {
    for (int c = 0; c < 2; ++c) {
      const int view = 2 * stop + c;
      const double theta_deg =
          360.0 * stop / stops + 0.013 * view;  // the encoder's angle, a little off the plan
      char name[64];
      std::snprintf(name, sizeof name, "frames/%03d_%s.png", view,
                    s.input.cameras[static_cast<size_t>(c)].serial.c_str());
      hairrig::CalibrationFrame input_frame;
      input_frame.path = input_frame.name = name;
      input_frame.view = view;
      input_frame.camera = c;
      input_frame.stop = stop;
      input_frame.turntable_deg = theta_deg;
      s.input.frames.push_back(input_frame);
      hairrig::FrameCalibration frame;
      frame.solved = view != s.failed_view;
      if (!frame.solved) {
        frame.failure = "2 tags matched to the box; a pose needs 3";
      } else {
        frame.cam_from_box = s.result.cameras[static_cast<size_t>(c)].cam_from_world *
                             hairrig::WorldFromTurntable(theta_deg) * s.result.turntable_from_box;
        frame.cam_from_box_init = frame.cam_from_box;
        frame.rms_px = 0.1;
      }
      s.result.frames.push_back(frame);
    }
  }
  return s;
}

}  // namespace hairrig_test
