#include "sim_hw/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "core/config.h"
#include "core/head_config.h"
#include "core/string_format.h"
#include "sim_hw/scene_variations.h"

namespace hairrig {

int Scene::FindCamera(const std::string& serial) const {
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].serial == serial) return static_cast<int>(i);
  }
  return -1;
}

namespace {

void ReadWig(const ConfigNode& n, const std::string& scene_path, WigOptions* w) {
  n.AllowOnlyKeys({"style",
                   "strands",
                   "length_mm",
                   "segment_mm",
                   "scalp_min_elevation_deg",
                   "face_dir",
                   "face_half_angle_deg",
                   "wave_amplitude_mm",
                   "wave_period_mm",
                   "curl_radius_mm",
                   "curl_pitch_mm",
                   "curl_left_share",
                   "wisps",
                   "clump",
                   "clump_profile",
                   "frizz_mm",
                   "flyaways",
                   "flyaway_mm",
                   "comb",
                   "bangs_depth_deg",
                   "bangs_length_mm",
                   "file",
                   "file_pose",
                   "fibre_diameter_um",
                   "albedo",
                   "seed"});
  const std::string style =
      n.Choice("style", {"straight", "wavy", "curly", "bangs", "file"}, "wavy");
  w->style = style == "straight" ? WigStyle::kStraight
             : style == "curly"  ? WigStyle::kCurly
             : style == "bangs"  ? WigStyle::kBangs
             : style == "file"   ? WigStyle::kFile
                                 : WigStyle::kWavy;
  w->num_strands = n.Integer("strands", w->num_strands, {.min = 1, .max = 2e6});
  if (n.Has("length_mm")) {
    const auto l = n.Numbers("length_mm", 2);
    if (l.size() == 2) {
      w->min_length_mm = l[0];
      w->max_length_mm = l[1];
      if (!(l[0] > 0 && l[1] >= l[0] && l[1] < 5000))
        n.Fail("length_mm", "expected [min, max] with 0 < min <= max < 5000");
    }
  }
  w->segment_mm = n.Number("segment_mm", w->segment_mm, {.min = 0.1, .max = 100});
  w->scalp_min_elevation_deg =
      n.Number("scalp_min_elevation_deg", w->scalp_min_elevation_deg, {.min = -90, .max = 89});
  w->face_dir = n.Vec3("face_dir", w->face_dir, kDirectionRange);
  if (w->face_dir.norm() < 1e-9) n.Fail("face_dir", "must not be the zero vector");
  w->face_dir.normalize();
  w->face_half_angle_deg =
      n.Number("face_half_angle_deg", w->face_half_angle_deg, {.min = 0, .max = 180});
  w->wave_amplitude_mm =
      n.Number("wave_amplitude_mm", w->wave_amplitude_mm, {.min = 0, .max = 200});
  w->wave_period_mm = n.Number("wave_period_mm", w->wave_period_mm, {.min = 1, .max = 2000});
  w->curl_radius_mm = n.Number("curl_radius_mm", w->curl_radius_mm, {.min = 0, .max = 200});
  w->curl_pitch_mm = n.Number("curl_pitch_mm", w->curl_pitch_mm, {.min = 0.5, .max = 2000});
  w->curl_left_share = n.Number("curl_left_share", w->curl_left_share, {.min = 0, .max = 1});
  w->wisps = n.Integer("wisps", w->wisps, {.min = 0, .max = 1e5});
  w->clump = n.Number("clump", w->clump, {.min = 0, .max = 1});
  w->clump_profile = n.Choice("clump_profile", {"tip", "middle"}, "tip") == "middle"
                         ? ClumpProfile::kMiddle
                         : ClumpProfile::kTip;
  w->frizz_mm = n.Number("frizz_mm", w->frizz_mm, {.min = 0, .max = 50});
  w->flyaway_fraction = n.Number("flyaways", w->flyaway_fraction, {.min = 0, .max = 1});
  w->flyaway_mm = n.Number("flyaway_mm", w->flyaway_mm, {.min = 0, .max = 500});
  w->comb = n.Number("comb", w->comb, {.min = 0, .max = 2});
  w->bangs_depth_deg = n.Number("bangs_depth_deg", w->bangs_depth_deg, {.min = 0, .max = 90});
  w->bangs_length_mm = n.Number("bangs_length_mm", w->bangs_length_mm, {.min = 5, .max = 1000});
  w->fibre_diameter_um =
      n.Number("fibre_diameter_um", w->fibre_diameter_um, {.min = 10, .max = 500});
  w->albedo = n.Vec3("albedo", w->albedo, kUnitRange);
  w->seed = static_cast<uint64_t>(n.Integer("seed", static_cast<int>(w->seed), {.min = 0}));
  if (w->style == WigStyle::kFile) {
    w->file = ResolveBesideFile(scene_path, n.String("file"));
    if (n.Has("file_pose")) w->turntable_from_file = ReadPoseConfig(n.Child("file_pose"));
  }
}

SceneCamera ReadCamera(const ConfigNode& n) {
  n.AllowOnlyKeys({"serial", "resolution", "intrinsics", "eye_mm", "target_mm", "read_noise_dn",
                   "shot_noise_gain", "exposure_s", "sensitivity"});
  SceneCamera c;
  c.serial = n.String("serial");
  const auto res = n.Numbers("resolution", 2);
  const ConfigNode in = n.Child("intrinsics");
  in.AllowOnlyKeys({"fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3"});
  if (res.size() == 2) {
    c.intrinsics.width_px = static_cast<int>(res[0]);
    c.intrinsics.height_px = static_cast<int>(res[1]);
    if (res[0] < 16 || res[1] < 16 || res[0] > 20000 || res[1] > 20000) {
      n.Fail("resolution", "expected [width, height] between 16 and 20000 pixels");
    }
  }
  c.intrinsics.fx_px = in.Number("fx_px", {.min = 1, .max = 1e6});
  c.intrinsics.fy_px = in.Number("fy_px", {.min = 1, .max = 1e6});
  c.intrinsics.cx_px = in.Number("cx_px", 0.5 * (c.intrinsics.width_px - 1), kPixelRange);
  c.intrinsics.cy_px = in.Number("cy_px", 0.5 * (c.intrinsics.height_px - 1), kPixelRange);
  c.intrinsics.k1 = in.Number("k1", 0.0, {.min = -2, .max = 2});
  c.intrinsics.k2 = in.Number("k2", 0.0, {.min = -2, .max = 2});
  c.intrinsics.p1 = in.Number("p1", 0.0, {.min = -0.1, .max = 0.1});
  c.intrinsics.p2 = in.Number("p2", 0.0, {.min = -0.1, .max = 0.1});
  c.intrinsics.k3 = in.Number("k3", 0.0, {.min = -2, .max = 2});
  const Eigen::Vector3d eye = n.Vec3("eye_mm", kPositionRangeMm);
  const Eigen::Vector3d target = n.Vec3("target_mm", kPositionRangeMm);
  if (n.ok() && (eye - target).norm() < 1.0)
    n.Fail("target_mm", "the camera must look somewhere: eye_mm equals target_mm");
  c.cam_from_world = LookAt(eye, target);
  c.target_distance_mm = (eye - target).norm();
  c.read_noise_dn = n.Number("read_noise_dn", c.read_noise_dn, {.min = 0, .max = 100});
  c.shot_noise_gain = n.Number("shot_noise_gain", c.shot_noise_gain, {.min = 0, .max = 10});
  c.exposure_s = n.Number("exposure_s", c.exposure_s, {.min = 1e-6, .max = 30});
  // DN per unit radiance per second / 255 (default 50): 1e6 is far beyond any sensor.
  c.sensitivity = n.Number("sensitivity", c.sensitivity, {.min = 1e-6, .max = 1e6});
  return c;
}

// calib_box.as_built: how the box in the images departs from its drawing,
// either drawn at random ({seed, tag_center_sd_mm, tag_turn_sd_deg,
// face_offset_sd_mm, face_tilt_sd_deg}) or read from a box file ({file}).
struct AsBuiltBox {
  std::string file;  // empty: drawn with `spread`
  BoxTolerance spread;
  uint64_t seed = 1;
};

// camera_pipeline: what every camera of the scene does between the light and
// its file (sim_hw/camera_pipeline.h).
CameraPipeline ReadCameraPipeline(const ConfigNode& n) {
  n.AllowOnlyKeys({"iso", "exposure_ev", "white_balance", "bayer", "tone", "jpeg_quality",
                   "f_number", "focus_mm", "pixel_um", "lens_blur_px", "render_grain_sd"});
  CameraPipeline p;
  p.iso = n.Number("iso", p.iso, {.min = 25, .max = 102400});
  p.exposure_ev = n.Number("exposure_ev", p.exposure_ev, {.min = -6, .max = 6});
  p.white_balance = n.Vec3("white_balance", p.white_balance, {.min = 0.1, .max = 10});
  p.bayer = n.Bool("bayer", p.bayer);
  p.tone = n.Choice("tone", {"linear", "srgb"}, "linear") == "srgb" ? CameraPipeline::Tone::kSrgb
                                                                    : CameraPipeline::Tone::kLinear;
  p.jpeg_quality = n.Integer("jpeg_quality", p.jpeg_quality, {.min = 0, .max = 100});
  if (n.Has("f_number")) p.f_number = n.Number("f_number", {.min = 0.7, .max = 64});
  p.focus_mm = n.Number("focus_mm", p.focus_mm, {.min = 0, .max = 1e6});
  p.pixel_um = n.Number("pixel_um", p.pixel_um, {.min = 0.5, .max = 100});
  p.lens_blur_px = n.Number("lens_blur_px", p.lens_blur_px, {.min = 0, .max = 20});
  p.render_grain_sd = n.Number("render_grain_sd", p.render_grain_sd, {.min = 0, .max = 2});
  return p;
}

AsBuiltBox ReadAsBuiltBox(const ConfigNode& box, const std::string& scene_path) {
  AsBuiltBox out;
  if (!box.Has("as_built")) return out;
  const ConfigNode a = box.Child("as_built");
  a.AllowOnlyKeys({"file", "seed", "tag_center_sd_mm", "tag_turn_sd_deg", "face_offset_sd_mm",
                   "face_tilt_sd_deg"});
  if (a.Has("file")) {
    out.file = ResolveBesideFile(scene_path, a.String("file"));
    return out;
  }
  out.seed = static_cast<uint64_t>(a.Integer("seed", 1, {.min = 0}));
  // A hand-built box: millimetres and degrees, not centimetres.
  out.spread.tag_center_mm = a.Number("tag_center_sd_mm", 0.0, {.min = 0, .max = 10});
  out.spread.tag_turn_deg = a.Number("tag_turn_sd_deg", 0.0, {.min = 0, .max = 10});
  out.spread.face_offset_mm = a.Number("face_offset_sd_mm", 0.0, {.min = 0, .max = 10});
  out.spread.face_tilt_deg = a.Number("face_tilt_sd_deg", 0.0, {.min = 0, .max = 10});
  return out;
}

// The box the renderer draws: the drawn one, or as built.
Result<CalibBox> BuildSceneBox(const CalibBox& drawn, const AsBuiltBox& as_built) {
  if (!as_built.file.empty()) {
    HR_ASSIGN_OR_RETURN(CalibBox built, LoadCalibBox(as_built.file));
    for (const BoxTag& tag : drawn.tags) {
      if (built.FindTag(tag.id) == nullptr)
        return InvalidArgument(as_built.file + ": the as-built box has no tag " +
                               std::to_string(tag.id) + ", which the drawn box has");
    }
    return built;
  }
  if (as_built.spread.Zero()) return drawn;
  return BuildBoxWithErrors(drawn, as_built.spread, as_built.seed);
}

}  // namespace

Status WigOptions::Check() const {
  // InvalidArgument unless lo <= value <= hi (NaN is outside).
  const auto range = [](const char* field, double value, double lo, double hi) {
    if (value >= lo && value <= hi) return Status::Ok();
    return InvalidArgument(
        StringPrintf("wig.%s must lie in [%g, %g], got %g", field, lo, hi, value));
  };
  HR_RETURN_IF_ERROR(range("strands", num_strands, 1, 2e6));
  if (!(min_length_mm > 0 && max_length_mm >= min_length_mm && max_length_mm < 5000))
    return InvalidArgument("wig.length_mm must be [min, max] with 0 < min <= max < 5000");
  HR_RETURN_IF_ERROR(range("segment_mm", segment_mm, 0.1, 100));
  HR_RETURN_IF_ERROR(range("scalp_min_elevation_deg", scalp_min_elevation_deg, -90, 89));
  if (!face_dir.allFinite() || face_dir.norm() < 1e-9)
    return InvalidArgument("wig.face_dir must be a finite, non-zero direction");
  HR_RETURN_IF_ERROR(range("face_half_angle_deg", face_half_angle_deg, 0, 180));
  HR_RETURN_IF_ERROR(range("wave_amplitude_mm", wave_amplitude_mm, 0, 200));
  HR_RETURN_IF_ERROR(range("wave_period_mm", wave_period_mm, 1, 2000));
  HR_RETURN_IF_ERROR(range("curl_radius_mm", curl_radius_mm, 0, 200));
  HR_RETURN_IF_ERROR(range("curl_pitch_mm", curl_pitch_mm, 0.5, 2000));
  HR_RETURN_IF_ERROR(range("curl_left_share", curl_left_share, 0, 1));
  HR_RETURN_IF_ERROR(range("wisps", wisps, 0, 1e5));
  HR_RETURN_IF_ERROR(range("clump", clump, 0, 1));
  HR_RETURN_IF_ERROR(range("frizz_mm", frizz_mm, 0, 50));
  HR_RETURN_IF_ERROR(range("flyaways", flyaway_fraction, 0, 1));
  HR_RETURN_IF_ERROR(range("flyaway_mm", flyaway_mm, 0, 500));
  HR_RETURN_IF_ERROR(range("comb", comb, 0, 2));
  HR_RETURN_IF_ERROR(range("bangs_depth_deg", bangs_depth_deg, 0, 90));
  HR_RETURN_IF_ERROR(range("bangs_length_mm", bangs_length_mm, 5, 1000));
  HR_RETURN_IF_ERROR(range("fibre_diameter_um", fibre_diameter_um, 10, 500));
  if (!(albedo.minCoeff() >= 0 && albedo.maxCoeff() <= 1))
    return InvalidArgument("wig.albedo must have every channel in [0, 1]");
  if (style == WigStyle::kFile && file.empty())
    return InvalidArgument("wig.file is required with style file");
  return Status::Ok();
}

Result<Scene> LoadScene(const std::string& path) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  root.AllowOnlyKeys({"name", "seed", "head", "wig", "hair_shading", "calib_box", "lights",
                      "cameras", "camera_pipeline", "backdrop_albedo", "ambient", "turntable",
                      "variations"});
  Scene scene;
  scene.path = path;
  scene.name = root.String("name", "unnamed scene");
  scene.seed = static_cast<uint64_t>(root.Integer("seed", 1, {.min = 0}));
  if (root.Has("head")) HR_RETURN_IF_ERROR(ReadHeadConfig(root, "head", path, &scene.head));
  if (root.Has("wig")) ReadWig(root.Child("wig"), path, &scene.wig);
  if (root.Has("hair_shading")) {
    const ConfigNode h = root.Child("hair_shading");
    h.AllowOnlyKeys({"model", "shadows", "cuticle_tilt_deg", "roughness_deg", "fibre_albedo_sd",
                     "fibre_grain_sd", "fibre_grain_mm"});
    HairShading& shading = scene.hair_shading;
    shading.model = h.Choice("model", {"marschner", "kajiya-kay"}, "marschner") == "kajiya-kay"
                        ? HairShading::Model::kKajiyaKay
                        : HairShading::Model::kMarschner;
    shading.shadows = h.Bool("shadows", shading.shadows);
    shading.cuticle_tilt_deg =
        h.Number("cuticle_tilt_deg", shading.cuticle_tilt_deg, {.min = -20, .max = 20});
    shading.roughness_deg = h.Number("roughness_deg", shading.roughness_deg, {.min = 1, .max = 45});
    shading.fibre_albedo_sd =
        h.Number("fibre_albedo_sd", shading.fibre_albedo_sd, {.min = 0, .max = 2});
    shading.fibre_grain_sd =
        h.Number("fibre_grain_sd", shading.fibre_grain_sd, {.min = 0, .max = 3});
    shading.fibre_grain_mm =
        h.Number("fibre_grain_mm", shading.fibre_grain_mm, {.min = 0.01, .max = 100});
  }
  const ConfigNode box = root.Child("calib_box");
  box.AllowOnlyKeys({"file", "turntable_from_box", "as_built"});
  const std::string box_file = ResolveBesideFile(path, box.String("file"));
  scene.turntable_from_box = ReadPoseConfig(box.Child("turntable_from_box"));
  const AsBuiltBox as_built = ReadAsBuiltBox(box, path);
  for (const ConfigNode& l : root.Items("lights")) {
    l.AllowOnlyKeys({"name", "position_mm", "intensity"});
    scene.lights.push_back({l.String("name"), l.Vec3("position_mm", kPositionRangeMm),
                            l.Number("intensity", 1.0, {.min = 0, .max = 1000})});
  }
  const CameraPipeline pipeline = root.Has("camera_pipeline")
                                      ? ReadCameraPipeline(root.Child("camera_pipeline"))
                                      : CameraPipeline();
  for (const ConfigNode& c : root.Items("cameras")) {
    scene.cameras.push_back(ReadCamera(c));
    scene.cameras.back().pipeline = pipeline;
  }
  scene.backdrop_albedo = root.Vec3("backdrop_albedo", scene.backdrop_albedo, kUnitRange);
  scene.ambient = root.Number("ambient", scene.ambient, {.min = 0, .max = 1});
  if (root.Has("turntable")) {
    const ConfigNode t = root.Child("turntable");
    t.AllowOnlyKeys({"stops", "speed_deg_s", "accel_deg_s2", "settle_s", "camera_readout_s",
                     "camera_download_s"});
    scene.turntable_stops = t.Integer("stops", scene.turntable_stops, {.min = 1, .max = 3600});
    // The rig config's limits for the same quantities (rig/capture_plan.cpp,
    // drivers/devices_common.cpp).
    scene.turntable_speed_deg_s =
        t.Number("speed_deg_s", scene.turntable_speed_deg_s, kTurntableSpeedRange);
    scene.turntable_accel_deg_s2 =
        t.Number("accel_deg_s2", scene.turntable_accel_deg_s2, kTurntableAccelRange);
    scene.turntable_settle_s =
        t.Number("settle_s", scene.turntable_settle_s, {.min = 0, .max = 60});
    scene.camera_readout_s =
        t.Number("camera_readout_s", scene.camera_readout_s, {.min = 0, .max = 60});
    scene.camera_download_s =
        t.Number("camera_download_s", scene.camera_download_s, {.min = 0, .max = 600});
  }
  if (!root.ok()) return root.status();
  HR_ASSIGN_OR_RETURN(scene.drawn_box, LoadCalibBox(box_file));
  HR_ASSIGN_OR_RETURN(scene.box, BuildSceneBox(scene.drawn_box, as_built));
  const std::vector<std::string> variations =
      root.Has("variations") ? root.Strings("variations") : std::vector<std::string>();
  HR_RETURN_IF_ERROR(root.status());
  HR_RETURN_IF_ERROR(
      ApplySceneVariations(variations, &scene).WithContext(root.Where() + ": field 'variations'"));
  HR_RETURN_IF_ERROR(ValidateScene(scene));
  return scene;
}

Status ValidateScene(const Scene& scene) {
  if (scene.cameras.empty()) return InvalidArgument(scene.path + ": the scene has no cameras");
  const Eigen::Vector3d half = 0.5 * scene.box.size_mm;
  for (const SceneCamera& cam : scene.cameras) {
    HR_RETURN_IF_ERROR(cam.intrinsics.Check().WithContext(scene.path + ": camera " + cam.serial));
    HR_RETURN_IF_ERROR(cam.pipeline.Check().WithContext(scene.path + ": camera " + cam.serial));
    for (int stop = 0; stop < scene.turntable_stops; ++stop) {
      const Rigid3d cam_from_box = cam.cam_from_world *
                                   WorldFromTurntable(scene.StopAngleDeg(stop)) *
                                   scene.turntable_from_box;
      for (const Eigen::Vector3d& p_box : BoxCornerPoints(half)) {
        if ((cam_from_box * p_box).z() < 10.0) {
          return InvalidArgument(
              scene.path + ": camera " + cam.serial + " has the calibration box behind it (or " +
              "closer than 10 mm) at turntable stop " + std::to_string(stop) +
              ": check calib_box.turntable_from_box and the camera's eye_mm/target_mm");
        }
      }
    }
  }
  // The box hangs above the head: its lowest corner clears the crown and the hair on it.
  constexpr double kHairOnCrownMm = 20.0;
  double box_bottom_mm = 1e30;
  for (const Eigen::Vector3d& p_box : BoxCornerPoints(half)) {
    box_bottom_mm = std::min(box_bottom_mm, (scene.turntable_from_box * p_box).z());
  }
  const double crown_mm =
      scene.head.center_turntable_mm.z() + scene.head.radii_mm.z() + kHairOnCrownMm;
  if (box_bottom_mm < crown_mm) {
    return InvalidArgument(
        scene.path +
        ": the calibration box (lowest corner at z = " + std::to_string(box_bottom_mm) +
        " mm) does not hang clear of the head and its hair (crown at z = " +
        std::to_string(crown_mm) + " mm): raise calib_box.turntable_from_box.translation_mm");
  }
  for (const SceneLight& l : scene.lights) {
    if (l.name.empty()) return InvalidArgument(scene.path + ": a light has no name");
  }
  return Status::Ok();
}

}  // namespace hairrig
