// The simulated rig's scene: what the cameras see, in millimetres and degrees
// (frames in core/transform.h). Loaded from etc/scenes/*.yaml; every number has
// a default so a scene file states only what it changes.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/status.h"
#include "core/strands.h"
#include "core/transform.h"

namespace hairrig {

struct SceneHead {
  Eigen::Vector3d center_turntable_mm{0, 0, 250};  // an ellipsoid on a stand
  Eigen::Vector3d radii_mm{78, 95, 115};
  Eigen::Vector3d albedo{0.80, 0.66, 0.56};  // linear RGB
};

enum class WigStyle { kStraight, kWavy, kCurly, kFile };

struct WigOptions {
  WigStyle style = WigStyle::kWavy;
  int num_strands = 10000;
  // Strand lengths along the fibre (waves and curls included), uniform in
  // [min, max]; points about segment_mm apart along it (curly: at least 12
  // per turn of the curl).
  double min_length_mm = 150;
  double max_length_mm = 260;
  double segment_mm = 5;
  // Scalp: directions from the head centre whose elevation is above this angle
  // (deg; 0 = equator, 90 = crown), and outside the face cone around `face_dir`.
  double scalp_min_elevation_deg = -5;
  Eigen::Vector3d face_dir{0, -1, 0};
  double face_half_angle_deg = 55;
  double wave_amplitude_mm = 4;   // wavy
  double wave_period_mm = 35;
  double curl_radius_mm = 5;      // curly
  double curl_pitch_mm = 14;
  std::string file;               // style kFile: a strand file (turntable frame, mm)
  Eigen::Vector3d albedo{0.30, 0.18, 0.09};
  uint64_t seed = 1;
};

struct SceneLight {
  std::string name;                 // "top", "bottom": matched to Light devices
  Eigen::Vector3d position_world_mm{0, 0, 1000};
  double intensity = 1.0;           // relative radiance scale
};

struct SceneCamera {
  std::string serial;               // matched to Camera devices by serial
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_world;
  double read_noise_dn = 1.5;       // std dev of additive noise, 8-bit DN
  double shot_noise_gain = 0.04;    // shot-noise variance per DN of signal
  double exposure_s = 0.02;         // nominal exposure
  double sensitivity = 50.0;        // DN per unit radiance per second / 255
};

struct Scene {
  std::string path;                 // file it came from (for messages)
  std::string name;
  uint64_t seed = 1;
  SceneHead head;
  WigOptions wig;
  CalibBox box;
  Rigid3d turntable_from_box;
  std::vector<SceneLight> lights;
  std::vector<SceneCamera> cameras;
  Eigen::Vector3d backdrop_albedo{0.08, 0.42, 0.12};  // keying green
  double ambient = 0.04;            // fraction of light from the room (0 when all panels are off)
  int turntable_stops = 19;
  // Realistic timings, scaled by the rig's time_scale in the simulated devices.
  double turntable_speed_deg_s = 30;
  double turntable_accel_deg_s2 = 60;
  double turntable_settle_s = 0.5;
  double camera_readout_s = 0.05;
  double camera_download_s = 0.25;

  int FindCamera(const std::string& serial) const;  // -1 if none
  double StopAngleDeg(int stop) const { return 360.0 * stop / turntable_stops; }
};

// Errors name the file, line and field; a camera that sees the box behind it or
// the box that intersects the head is refused with the reason.
Result<Scene> LoadScene(const std::string& path);
// Checks geometry that a parser cannot see (box in front of every camera, box
// clear of the head, intrinsics valid).
Status ValidateScene(const Scene& scene);

}  // namespace hairrig
