#include "sim_hw/scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

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
      {"settle_s: 0.5", "settle_s: .nan", "turntable.settle_s"}};
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

}  // namespace
}  // namespace hairrig
