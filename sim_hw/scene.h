// The simulated rig's scene: what the cameras see, in millimetres and degrees
// (frames in core/transform.h). Loaded from etc/scenes/*.yaml; every number has
// a default so a scene file states only what it changes.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/calib_box.h"
#include "core/camera_model.h"
#include "core/head_spec.h"
#include "core/status.h"
#include "core/strands.h"
#include "core/transform.h"
#include "sim_hw/camera_pipeline.h"

namespace hairrig {

enum class WigStyle { kStraight, kWavy, kCurly, kBangs, kFile };
enum class ClumpProfile { kTip, kMiddle };

struct WigOptions {
  WigStyle style = WigStyle::kWavy;
  int num_strands = 10000;
  // Strand lengths along the fibre (waves and curls included), uniform in
  // [min, max]; points about segment_mm apart along it (curly: at least 12
  // per turn of the curl).
  double min_length_mm = 150;
  double max_length_mm = 260;
  double segment_mm = 5;
  // Roots where the head has no `scalp`: directions from the head centre whose
  // elevation is above this angle (deg; 0 = equator, 90 = crown), and outside
  // the face cone around `face_dir`.
  double scalp_min_elevation_deg = -5;
  Eigen::Vector3d face_dir{0, -1, 0};
  double face_half_angle_deg = 55;
  double wave_amplitude_mm = 4;  // wavy
  double wave_period_mm = 35;
  double curl_radius_mm = 5;  // curly: ringlets of twice this diameter
  double curl_pitch_mm = 14;
  // The share of the strands (of the wisps, with wisps) whose curls wind
  // left-handed; the others wind right-handed.
  double curl_left_share = 0;
  // Wisps: strands clumped around `wisps` wisp centres (0: every strand on its
  // own). A member keeps its root's offset from the wisp's root in the wisp's
  // frame, shrunk by `clump` (0..1) where the profile is tightest: at the tip,
  // or in the middle (spread again towards the tip).
  int wisps = 0;
  ClumpProfile clump_profile = ClumpProfile::kTip;
  double clump = 0.7;
  double frizz_mm = 0;          // random sideways wander of each fibre, growing to this at the tip
  double flyaway_fraction = 0;  // share of strands that leave their wisp in a loose arc
  double flyaway_mm = 25;       // how far a flyaway's tip strays
  double comb = 0.6;            // how strongly hair leaves the parting sideways (0..2)
  // Bangs (style kBangs): strands rooted within `bangs_depth_deg` above the
  // front hairline (and within 60 deg of the face) fall forward over the
  // forehead, `bangs_length_mm` long; the rest falls as straight hair.
  double bangs_depth_deg = 22;
  double bangs_length_mm = 95;
  // Style kFile: a strand file whose strands are the wisp guides, placed by
  // `turntable_from_file`; `num_strands` members are grown around them (the
  // file's own strands alone when num_strands is not larger than their count).
  std::string file;
  Rigid3d turntable_from_file;
  double fibre_diameter_um = 70;
  Eigen::Vector3d albedo{0.30, 0.18, 0.09};  // linear RGB of the fibre (its absorption colour)
  uint64_t seed = 1;

  // InvalidArgument naming the scene file's field (wig.strands, wig.length_mm,
  // ...) for a value outside the range LoadScene accepts, or style file
  // without wig.file.
  Status Check() const;
};

// How hair fibres are shaded and shadowed (sim_hw/renderer.h).
struct HairShading {
  // kMarschner: R, TT and TRT lobes (Marschner et al. 2003, in the simplified
  // form of Sadeghi et al. 2010); kKajiyaKay: one diffuse and one specular
  // lobe (Kajiya & Kay 1989), for comparison.
  enum class Model { kMarschner, kKajiyaKay };
  Model model = Model::kMarschner;
  // Deep opacity maps from each LED panel: the hair shadows itself and the head.
  bool shadows = true;
  double cuticle_tilt_deg =
      -5;  // alpha: R shifts by alpha, TT by -alpha/2, TRT by -3 alpha/2 (towards the root)
  double roughness_deg = 7;  // beta: R's longitudinal width; TT beta/2, TRT 2 beta
  // Fibre-level appearance: each fibre's colour scaled by its own factor (log-
  // normal, mean 1, this sd of the log), and its radiance along it by a grain
  // of glints and dull stretches `fibre_grain_mm` long (log-normal, sd of the
  // log fibre_grain_sd), finer than a pixel. 0: every fibre alike and smooth.
  double fibre_albedo_sd = 0;
  double fibre_grain_sd = 0;
  double fibre_grain_mm = 0.5;
};

struct SceneLight {
  std::string name;  // "top", "bottom": matched to Light devices
  Eigen::Vector3d position_world_mm{0, 0, 1000};
  double intensity = 1.0;  // relative radiance scale
};

struct SceneCamera {
  std::string serial;  // matched to Camera devices by serial
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_world;
  double read_noise_dn = 1.5;        // std dev of additive noise, 8-bit DN
  double shot_noise_gain = 0.04;     // shot-noise variance per DN of signal
  double exposure_s = 0.02;          // nominal exposure
  double sensitivity = 50.0;         // DN per unit radiance per second / 255
  double target_distance_mm = 1000;  // from the eye to the point it looks at (the focus)
  CameraPipeline pipeline;           // the scene's camera_pipeline
};

struct Scene {
  std::string path;  // file it came from (for messages)
  std::string name;
  uint64_t seed = 1;
  HeadSpec head;
  WigOptions wig;
  HairShading hair_shading;
  // The box the images show, as built (calib_box.as_built), and as drawn
  // (calib_box.file: what a calibration is given). The same box unless the
  // scene says how it was built.
  CalibBox box;
  CalibBox drawn_box;
  Rigid3d turntable_from_box;
  std::vector<SceneLight> lights;
  std::vector<SceneCamera> cameras;
  Eigen::Vector3d backdrop_albedo{0.08, 0.42, 0.12};  // keying green
  double ambient = 0.04;  // fraction of light from the room (0 when all panels are off)
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
// the box that intersects the head is refused with the reason. Every number
// has a range far beyond any real rig (positions within 100 m, the turntable's
// and cameras' timings within the rig config's limits, core/config.h).
Result<Scene> LoadScene(const std::string& path);
// Checks geometry that a parser cannot see (box in front of every camera, box
// clear of the head, intrinsics valid).
Status ValidateScene(const Scene& scene);

}  // namespace hairrig
