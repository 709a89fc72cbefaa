#include "core/config.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(Config, ReadsFieldsAndNamesTheLineOfABadOne) {
  auto root = ConfigNode::LoadString("camera:\n  fx_px: 1200\n  fy_px: abc\n", "rig.yaml");
  ASSERT_TRUE(root.ok());
  const ConfigNode camera = root->Child("camera");
  EXPECT_EQ(camera.Number("fx_px"), 1200.0);
  EXPECT_TRUE(root->ok());
  camera.Number("fy_px", {.min = 1});
  ASSERT_FALSE(root->ok());
  const std::string m = root->status().message();
  EXPECT_NE(m.find("rig.yaml:3:"), std::string::npos) << m;
  EXPECT_NE(m.find("camera.fy_px"), std::string::npos) << m;
  EXPECT_NE(m.find("'abc'"), std::string::npos) << m;
}

TEST(Config, BrokenYamlNamesTheFileAndLine) {
  auto root = ConfigNode::LoadString("a: [1, 2\nb: 3\n", "broken.yaml");
  ASSERT_FALSE(root.ok());
  EXPECT_NE(root.status().message().find("broken.yaml:"), std::string::npos) << root.status().message();
}

TEST(Config, RefusesNanRangeAndUnknownKeys) {
  auto root = ConfigNode::LoadString("x: .nan\n", "f.yaml");
  ASSERT_TRUE(root.ok());
  root->Number("x");
  EXPECT_FALSE(root->ok());

  auto r2 = ConfigNode::LoadString("x: -3\n", "f.yaml");
  r2->Number("x", {.min = 0});
  EXPECT_NE(r2->status().message().find(">= 0"), std::string::npos);

  auto r3 = ConfigNode::LoadString("fx: 3\n", "f.yaml");
  r3->AllowOnlyKeys({"fx_px"});
  EXPECT_NE(r3->status().message().find("unknown field 'fx'"), std::string::npos) << r3->status().message();
}

TEST(Config, ItemsCarryTheirIndexInThePath) {
  auto root = ConfigNode::LoadString("cams:\n  - {w: 1}\n  - {w: x}\n", "f.yaml");
  const auto items = root->Items("cams");
  ASSERT_EQ(items.size(), 2u);
  items[1].Integer("w");
  EXPECT_NE(root->status().message().find("cams[1].w"), std::string::npos) << root->status().message();
}

TEST(Config, KeysComeInFileOrder) {
  auto root = ConfigNode::LoadString("settings: {iso: 100, aperture: 8, imageformat: RAW}\nx: 1\n", "f.yaml");
  ASSERT_TRUE(root.ok());
  EXPECT_EQ(root->Child("settings").Keys(), (std::vector<std::string>{"iso", "aperture", "imageformat"}));
  EXPECT_TRUE(root->OptionalChild("absent").Keys().empty());
}

TEST(Config, MissingFileIsNotFound) {
  auto root = ConfigNode::LoadFile("/nonexistent/rig.yaml");
  EXPECT_EQ(root.status().code(), StatusCode::kNotFound);
}

TEST(Config, ChoiceListsTheAllowedValues) {
  auto root = ConfigNode::LoadString("backend: sum\n", "f.yaml");
  root->Choice("backend", {"sim", "modbus"});
  EXPECT_NE(root->status().message().find("sim, modbus"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
