#include "sim_hw/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "sim_hw/deep_opacity.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/quota_storage.h"
#include "sim_hw/renderer.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_server.h"
#include "sim_hw/sim_v4l2.h"
#include "sim_hw/view_set.h"
#include "sim_hw/wig.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// The small test scene (tests/data/small_scene.yaml) with the first `from`
// replaced by `to`, written into the test's temporary folder; its path.
std::string SmallSceneWith(const std::string& name, const std::string& from,
                           const std::string& to) {
  std::ifstream in("tests/data/small_scene.yaml");
  std::string text(std::istreambuf_iterator<char>(in), {});
  const std::string box = "file: ../../etc/calib-box.yaml";
  const size_t box_at = text.find(box);
  EXPECT_NE(box_at, std::string::npos);
  if (box_at != std::string::npos)
    text.replace(box_at, box.size(), "file: " + fs::absolute("etc/calib-box.yaml").string());
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  const std::string path = ::testing::TempDir() + "/scene_" + name + ".yaml";
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

TEST(Scene, TheSmallSceneLoads) {
  const auto scene = LoadScene(SmallSceneWith("small", "name: small", "name: small"));
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  EXPECT_EQ(scene->cameras.size(), 2u);
}

// calib_box.as_built: the images show a box off its drawing, the scene keeps
// the drawn one for the calibration; the same seed gives the same box.
TEST(Scene, ABoxAsBuiltDepartsFromTheDrawnOne) {
  const auto scene = LoadScene("etc/scenes/hand_built_box.yaml");
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  const auto drawn = LoadCalibBox("etc/calib-box.yaml");
  ASSERT_TRUE(drawn.ok()) << drawn.status().ToString();
  double largest_mm = 0;
  for (const BoxTag& tag : drawn->tags) {
    EXPECT_EQ(scene->drawn_box.FindTag(tag.id)->corners_box_mm[0], tag.corners_box_mm[0]);
    const BoxTag& built = *scene->box.FindTag(tag.id);
    largest_mm = std::max(largest_mm, (built.center_box_mm - tag.center_box_mm).norm());
  }
  EXPECT_GT(largest_mm, 0.5);
  EXPECT_LT(largest_mm, 5.0);
  const auto again = LoadScene("etc/scenes/hand_built_box.yaml");
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->box.tags[3].corners_box_mm[2], scene->box.tags[3].corners_box_mm[2]);
  const std::string box_line = "file: " + fs::absolute("etc/calib-box.yaml").string();
  const std::string path = SmallSceneWith(
      "as_built_typo", box_line, box_line + "\n  as_built: {seed: 2, tag_centre_sd_mm: 0.5}");
  const auto typo = LoadScene(path);
  ASSERT_FALSE(typo.ok());
  EXPECT_NE(typo.status().message().find("tag_centre_sd_mm"), std::string::npos)
      << typo.status().ToString();
}

// Numbers no real rig comes near (1e300 overflows the geometry and the
// timings) are refused, naming the file and the field.
TEST(Scene, NumbersBeyondAnyRigAreRefusedNamingTheFileAndField) {
  struct Case {
    std::string from, to, field;
  };
  const std::vector<Case> cases = {
      {"eye_mm: [900, 0, 700]", "eye_mm: [1e300, 0, 700]", "cameras[0].eye_mm"},
      {"target_mm: [0, 0, 390]", "target_mm: [0, -1e300, 390]", "cameras[0].target_mm"},
      {"fx_px: 437.5", "fx_px: 1e300", "cameras[0].intrinsics.fx_px"},
      {"cx_px: 150.1", "cx_px: 1e300", "cameras[0].intrinsics.cx_px"},
      {"read_noise_dn: 1.5", "read_noise_dn: 1.5\n    sensitivity: 1e300",
       "cameras[0].sensitivity"},
      {"intensity: 0.85", "intensity: 1e300", "lights[0].intensity"},
      {"position_mm: [600, 0, 1300]", "position_mm: [600, 0, 1e300]", "lights[0].position_mm"},
      {"backdrop_albedo: [0.08, 0.42, 0.12]", "backdrop_albedo: [0.08, 1e300, 0.12]",
       "backdrop_albedo"},
      {"center_mm: [0, 0, 330]", "center_mm: [0, 0, 1e300]", "head.center_mm"},
      {"radii_mm: [78, 95, 115]", "radii_mm: [78, 1e300, 115]", "head.radii_mm"},
      {"translation_mm: [0, 0, 600]", "translation_mm: [0, 0, 1e300]",
       "calib_box.turntable_from_box.translation_mm"},
      {"rotation_deg: [0, 0, 10]", "rotation_deg: [0, 0, 1e300]",
       "calib_box.turntable_from_box.rotation_deg"},
      {"speed_deg_s: 30", "speed_deg_s: 1e300", "turntable.speed_deg_s"},
      {"accel_deg_s2: 60", "accel_deg_s2: 1e300", "turntable.accel_deg_s2"},
      {"settle_s: 0.5", "settle_s: 1e300", "turntable.settle_s"},
      {"camera_readout_s: 0.05", "camera_readout_s: 1e300", "turntable.camera_readout_s"},
      {"camera_download_s: 0.25", "camera_download_s: 1e300", "turntable.camera_download_s"},
      {"speed_deg_s: 30", "speed_deg_s: -1", "turntable.speed_deg_s"},
      {"settle_s: 0.5", "settle_s: .nan", "turntable.settle_s"},
      {"ambient: 0.05", "ambient: 0.05\ncamera_pipeline: {jpeg_quality: 101}",
       "camera_pipeline.jpeg_quality"},
      {"ambient: 0.05", "ambient: 0.05\ncamera_pipeline: {iso: .nan}", "camera_pipeline.iso"},
      {"ambient: 0.05", "ambient: 0.05\nhair_shading: {fibre_grain_sd: 1e300}",
       "hair_shading.fibre_grain_sd"}};
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const std::string path = SmallSceneWith("range_" + std::to_string(i), c.from, c.to);
    const auto scene = LoadScene(path);
    ASSERT_FALSE(scene.ok()) << c.to;
    EXPECT_EQ(scene.status().code(), StatusCode::kInvalidArgument) << scene.status().ToString();
    EXPECT_NE(scene.status().message().find(path + ":"), std::string::npos)
        << scene.status().ToString();
    EXPECT_NE(scene.status().message().find("field '" + c.field + "'"), std::string::npos)
        << scene.status().ToString();
  }
}

// camera_pipeline applies to every camera; variations come after the file's
// own values; an unknown variation is named with the known ones.
TEST(Scene, CameraPipelineAndVariations) {
  const auto scene = LoadScene(SmallSceneWith(
      "pipeline", "ambient: 0.05",
      "ambient: 0.05\ncamera_pipeline: {jpeg_quality: 90, iso: 400}\nvariations: [grey_backdrop, "
      "bayer]"));
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  for (const SceneCamera& camera : scene->cameras) {
    EXPECT_EQ(camera.pipeline.jpeg_quality, 90);
    EXPECT_EQ(camera.pipeline.iso, 400);
    EXPECT_TRUE(camera.pipeline.bayer);
  }
  EXPECT_EQ(scene->backdrop_albedo, Eigen::Vector3d(0.3, 0.3, 0.3));
  const std::string path =
      SmallSceneWith("unknown_variation", "ambient: 0.05", "ambient: 0.05\nvariations: [nope]");
  const auto refused = LoadScene(path);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  for (const std::string& part :
       {path, std::string("'variations'"), std::string("'nope'"), std::string("photograph")})
    EXPECT_NE(refused.status().message().find(part), std::string::npos)
        << refused.status().ToString();
}

// The simulated rig's options refuse a bad value with InvalidArgument naming
// the field; their defaults pass (the cameras' once they have a serial).
TEST(SimOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(ShadowMapOptions{}.Check().ok());
  EXPECT_TRUE(QuotaStorageOptions{}.Check().ok());
  EXPECT_TRUE(RenderOptions{}.Check().ok());
  EXPECT_TRUE(RenderViewsOptions{}.Check().ok());
  EXPECT_TRUE(WigOptions{}.Check().ok());
  EXPECT_TRUE(SimWorldOptions{}.Check().ok());
  EXPECT_TRUE(ModbusServerOptions{}.Check().ok());
  EXPECT_TRUE(SimV4l2Options{}.Check().ok());
  {
    ShadowMapOptions o;
    o.layers = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "layers"));
    o = ShadowMapOptions{};
    o.layer_mm = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "layer_mm"));
  }
  {
    QuotaStorageOptions o;
    o.frame_files = -2;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "frame_files"));
  }
  {
    RenderOptions o;
    o.light_levels = {1.0, 1.5};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "light_levels[1]"));
    o = RenderOptions{};
    o.exposure_s = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "exposure_s"));
    o = RenderOptions{};
    o.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
  }
  {
    RenderViewsOptions o;
    o.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
    RenderSceneViewsOptions scene_views;
    scene_views.scene_file = "scene.yaml";
    scene_views.out_dir = "out";
    EXPECT_TRUE(scene_views.Check().ok()) << scene_views.Check().ToString();
    scene_views.render.light_levels = {-1.0};
    EXPECT_TRUE(IsInvalidNaming(scene_views.Check(), "render: light_levels[0]"));
  }
  {
    WigOptions o;
    o.segment_mm = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "wig.segment_mm"));
    o = WigOptions{};
    o.min_length_mm = 300;
    o.max_length_mm = 200;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "wig.length_mm"));
    o = WigOptions{};
    o.clump = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "wig.clump"));
    o = WigOptions{};
    o.style = WigStyle::kFile;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "wig.file"));
  }
  {
    SimWorldOptions o;
    o.time_scale = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "time_scale"));
    o = SimWorldOptions{};
    SimFault fault;
    fault.count = 0;
    o.faults = {fault};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "faults[0].count"));
  }
  {
    ModbusServerOptions o;
    o.slave_id = 248;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "slave_id"));
    o = ModbusServerOptions{};
    o.serial = std::string(40, 'S');
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "serial"));
  }
  {
    SimAravisOptions o;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "serial"));
    o.serial = "SIM-1";
    EXPECT_TRUE(o.Check().ok());
    o.scene_camera = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "scene_camera"));
  }
  {
    SimDslrOptions o;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "serial"));
    o.serial = "SIM-1";
    EXPECT_TRUE(o.Check().ok());
    o.reply_timeout_ms = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "reply_timeout_ms"));
  }
  {
    SimV4l2Options o;
    o.fps = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "fps"));
    o = SimV4l2Options{};
    o.node.clear();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "node"));
  }
}

// The entry points taking the options refuse bad ones before any work.
TEST(SimOptions, EntryPointsCheckTheirOptions) {
  WigOptions wig;
  wig.num_strands = 0;
  const Result<StrandSet> strands = GenerateWig(wig, HeadSpec{});
  ASSERT_FALSE(strands.ok());
  EXPECT_NE(strands.status().message().find("wig.strands"), std::string::npos)
      << strands.status().ToString();

  SimWorldOptions world;
  world.time_scale = -1;
  const auto created = CreateSimWorld(Scene{}, world);
  ASSERT_FALSE(created.ok());
  EXPECT_NE(created.status().message().find("time_scale"), std::string::npos);

  RenderSceneViewsOptions views;
  views.scene_file = "scene.yaml";
  views.out_dir = ::testing::TempDir() + "/sim_options_views";
  views.render.threads = 0;
  const auto rendered = RenderSceneViews(views);
  ASSERT_FALSE(rendered.ok());
  EXPECT_NE(rendered.status().message().find("render: threads"), std::string::npos)
      << rendered.status().ToString();
}

}  // namespace
}  // namespace hairrig
