// Small calibration documents for tests: a 640 x 480 camera, a
// calibration.json with a solved and a failed view (turntable mode, standard
// deviations and per-view uncertainty), and an intrinsics file as
// `hairrig calibrate-intrinsics` writes it. Shared by the readers' unit tests
// and the parser fuzz test's seeds.
#pragma once

#include <nlohmann/json.hpp>

#include "core/camera_model.h"
#include "core/geometry_json.h"
#include "core/transform.h"

namespace hairrig_test {

inline hairrig::CameraIntrinsics SmallTestIntrinsics() {
  using hairrig::CameraIntrinsics;
  CameraIntrinsics k;
  k.width_px = 640;
  k.height_px = 480;
  k.fx_px = k.fy_px = 800;
  k.cx_px = 320;
  k.cy_px = 240;
  k.k1 = -0.1;
  return k;
}

inline nlohmann::json CalibrationDocument() {
  using hairrig::IntrinsicsToJson;
  using hairrig::PoseToJson;
  using hairrig::Rigid3d;
  using nlohmann::json;
  const json camera = {{"name", "upper"},
                       {"serial", "CAM-UPPER"},
                       {"solved", true},
                       {"intrinsics", IntrinsicsToJson(SmallTestIntrinsics())},
                       {"intrinsics_initial", IntrinsicsToJson(SmallTestIntrinsics())},
                       {"intrinsics_stddev", {{"fx_px", 0.5}, {"k1", 0.01}}}};
  const json view = {{"view", 0},
                     {"camera", 0},
                     {"frame", "frames/000_CAM-UPPER.png"},
                     {"solved", true},
                     {"cam_from_box", PoseToJson(Rigid3d())},
                     {"cam_from_box_initial", PoseToJson(Rigid3d())},
                     {"cam_from_object", PoseToJson(Rigid3d())},
                     {"rms_px", 0.3},
                     {"uncertainty", {{"rotation_sd_deg", 0.01}, {"centre_sd_mm", 0.1}}},
                     {"tags", {{{"id", 4}, {"corners_px", {{1, 2}, {3, 4}, {5, 6}, {7, 8}}}}}}};
  const json failed = {{"view", 1},
                       {"camera", 0},
                       {"frame", "frames/001_CAM-UPPER.png"},
                       {"solved", false},
                       {"failure", "no tags"}};
  return {{"format", "hairrig-calibration"},
          {"version", 1},
          {"mode", "turntable"},
          {"rms_px", 0.3},
          {"turntable_from_box", PoseToJson(Rigid3d())},
          {"cameras", {camera}},
          {"views", {view, failed}}};
}

inline nlohmann::json IntrinsicsDocument() {
  using hairrig::IntrinsicsToJson;
  return {{"format", "hairrig-intrinsics"},
          {"version", 1},
          {"serial", "CAM-UPPER"},
          {"intrinsics", IntrinsicsToJson(SmallTestIntrinsics())},
          {"intrinsics_stddev", {{"fx_px", 0.5}, {"fy_px", 0.5}}},
          {"rms_px", 0.2}};
}

}  // namespace hairrig_test
