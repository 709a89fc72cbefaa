#include "core/config.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

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
  EXPECT_NE(root.status().message().find("broken.yaml:"), std::string::npos)
      << root.status().message();
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
  EXPECT_NE(r3->status().message().find("unknown field 'fx'"), std::string::npos)
      << r3->status().message();
}

TEST(Config, ItemsCarryTheirIndexInThePath) {
  auto root = ConfigNode::LoadString("cams:\n  - {w: 1}\n  - {w: x}\n", "f.yaml");
  const auto items = root->Items("cams");
  ASSERT_EQ(items.size(), 2u);
  items[1].Integer("w");
  EXPECT_NE(root->status().message().find("cams[1].w"), std::string::npos)
      << root->status().message();
}

TEST(Config, KeysComeInFileOrder) {
  auto root = ConfigNode::LoadString("settings: {iso: 100, aperture: 8, imageformat: RAW}\nx: 1\n",
                                     "f.yaml");
  ASSERT_TRUE(root.ok());
  EXPECT_EQ(root->Child("settings").Keys(),
            (std::vector<std::string>{"iso", "aperture", "imageformat"}));
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

// The message of loading `text`, which must be refused.
std::string Refusal(const std::string& text) {
  auto root = ConfigNode::LoadString(text, "rig.yaml");
  EXPECT_FALSE(root.ok()) << text;
  return root.ok() ? "" : root.status().message();
}

TEST(Config, DuplicateKeysAreErrorsAtTheSecondOne) {
  std::string m = Refusal("name: a\ndevices: {}\nname: b\n");
  EXPECT_NE(m.find("rig.yaml:3:1: duplicate key 'name' (first at line 1)"), std::string::npos) << m;
  m = Refusal("plan:\n  stops: 3\n  lights: {top: 1, top: 0}\n");
  EXPECT_NE(m.find("rig.yaml:3:20: duplicate key 'top'"), std::string::npos) << m;
  m = Refusal("sim: {a: 1}\nplan: {}\nsim: {b: 2}\n");
  EXPECT_NE(m.find("rig.yaml:3:1: duplicate key 'sim'"), std::string::npos) << m;
  // The same key in two maps is two keys.
  EXPECT_TRUE(
      ConfigNode::LoadString("a: {x: 1}\nb: {x: 2}\nc: [{x: 1}, {x: 2}]\n", "rig.yaml").ok());
}

TEST(Config, ASecondDocumentIsAnError) {
  const std::string m = Refusal("name: a\n---\nname: b\n");
  EXPECT_NE(m.find("rig.yaml:2:1: a second YAML document"), std::string::npos) << m;
  EXPECT_TRUE(ConfigNode::LoadString("---\nname: a\n...\n", "rig.yaml").ok());
}

TEST(Config, KeysMustBeText) {
  EXPECT_NE(Refusal("? [a, b]\n: 1\n").find("rig.yaml:1:3: a map key must be text"),
            std::string::npos);
}

TEST(Config, SizeDepthAndValueCountAreBounded) {
  std::string deep = "a: ";
  for (int i = 0; i < 100; ++i) deep += "[";
  EXPECT_NE(Refusal(deep + std::string(100, ']') + "\n").find("nested deeper than"),
            std::string::npos);
  std::string many = "angles_deg: [";
  for (int i = 0; i <= kMaxConfigValues; ++i) many += "0,";
  EXPECT_NE(Refusal(many + "0]\n").find("more than"), std::string::npos);
  EXPECT_NE(Refusal("a: '" + std::string(kMaxConfigBytes, 'x') + "'\n").find("bytes"),
            std::string::npos);
}

TEST(Config, MessagesQuoteAnExcerptNeverAWholeFile) {
  const std::string file(5000, 'x');
  std::string m = Refusal(file);
  EXPECT_LT(m.size(), 200u) << m;
  EXPECT_NE(m.find("got text of 5000 bytes"), std::string::npos) << m;
  // A file named by mistake reads as one long scalar: its content is never repeated.
  m = Refusal("root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n");
  EXPECT_EQ(m, "rig.yaml: expected a YAML map at the top level, got text of 79 bytes");
  EXPECT_NE(Refusal("a\tb\n").find("got text of 3 bytes"), std::string::npos);
  auto root = ConfigNode::LoadString("fx_px: \"" + std::string(3000, 'y') + "\"\n", "rig.yaml");
  ASSERT_TRUE(root.ok());
  root->Number("fx_px");
  EXPECT_LT(root->status().message().size(), 200u) << root->status().message();
  EXPECT_EQ(QuotedExcerpt("a\tb"), "'a?b'");
  EXPECT_EQ(QuotedExcerpt(std::string(61, 'z')), "'" + std::string(60, 'z') + "...' (61 bytes)");
  // A cut never splits a UTF-8 character: 'é' is 2 bytes, 59 + 2 crosses 60.
  EXPECT_EQ(QuotedExcerpt(std::string(59, 'z') + "\xC3\xA9z"),
            "'" + std::string(59, 'z') + "...' (62 bytes)");
}

// Config text ends up in JSON files (capture.json, reports), which hold UTF-8
// only: text that is not is refused where it is read, naming its field.
TEST(Config, TextMustBeValidUtf8) {
  std::string m = Refusal("name: ok\nrig:\n  name: caf\xE9\n");
  EXPECT_EQ(m,
            "rig.yaml:3:9: field 'rig.name': text that is not valid UTF-8; save the file as UTF-8");
  m = Refusal("cameras:\n  - {serial: \"\xC0\xAF\"}\n");  // an overlong '/'
  EXPECT_NE(m.find("rig.yaml:2:14: field 'cameras[0].serial': text that is not valid UTF-8"),
            std::string::npos)
      << m;
  m = Refusal("a:\n  - [1, \"x\xED\xA0\x80y\"]\n");  // a UTF-16 surrogate
  EXPECT_NE(m.find("field 'a[0][1]'"), std::string::npos) << m;
  EXPECT_NE(Refusal("caf\xE9: 1\n").find("rig.yaml:1:1: a key in '<top>'"), std::string::npos);
  EXPECT_NE(Refusal("name: \"\xF4\x90\x80\x80\"\n").find("not valid UTF-8"),
            std::string::npos);  // > U+10FFFF
  EXPECT_TRUE(ConfigNode::LoadString("name: caf\xC3\xA9 \xF0\x9F\x98\x80\n", "rig.yaml").ok());
}

TEST(Config, ListElementsAreCheckedAgainstTheRange) {
  auto root = ConfigNode::LoadString("angles_deg: [0, 1e12]\n", "rig.yaml");
  ASSERT_TRUE(root.ok());
  EXPECT_TRUE(root->Numbers("angles_deg", 0, {.min = -3600, .max = 3600}).empty());
  const std::string m = root->status().message();
  EXPECT_NE(m.find("element 1: expected a number in [-3600, 3600], got '1e12'"), std::string::npos)
      << m;
}

// A point's coordinates have a range, as a single number does: 1e300 mm is refused.
TEST(Config, Vec3ElementsAreCheckedAgainstTheRange) {
  auto root = ConfigNode::LoadString("eye_mm: [900, 1e300, 700]\n", "scene.yaml");
  ASSERT_TRUE(root.ok());
  EXPECT_EQ(root->Vec3("eye_mm", Eigen::Vector3d::Zero(), kPositionRangeMm),
            Eigen::Vector3d::Zero());
  const std::string m = root->status().message();
  EXPECT_NE(m.find("scene.yaml:1:"), std::string::npos) << m;
  EXPECT_NE(m.find("field 'eye_mm': element 1: expected a number in [-100000, 100000], got "
                   "'1e300'"),
            std::string::npos)
      << m;
  auto fine = ConfigNode::LoadString("eye_mm: [900, 0, 700]\n", "scene.yaml");
  EXPECT_EQ(fine->Vec3("eye_mm", kPositionRangeMm), Eigen::Vector3d(900, 0, 700));
  EXPECT_TRUE(fine->ok());
}

TEST(Config, UnknownKeysListTheKnownOnes) {
  auto root = ConfigNode::LoadString("plan:\n  stpos: 3\n", "rig.yaml");
  root->Child("plan").AllowOnlyKeys({"stops", "angles_deg"});
  EXPECT_EQ(root->status().message(),
            "rig.yaml:2:3: unknown field 'plan.stpos' (expected one of: stops, angles_deg)");
}

TEST(Config, OnlyRegularFilesAreRead) {
  for (const char* path : {"/dev/zero", "/dev/urandom", "/"}) {
    auto root = ConfigNode::LoadFile(path);
    ASSERT_FALSE(root.ok()) << path;
    EXPECT_NE(root.status().message().find("not a regular file"), std::string::npos)
        << root.status().message();
  }
  const std::string fifo =
      (std::filesystem::temp_directory_path() / ("config_test_fifo_" + std::to_string(getpid())))
          .string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  auto root = ConfigNode::LoadFile(fifo);  // a blocking open would wait here for a writer
  unlink(fifo.c_str());
  ASSERT_FALSE(root.ok());
  EXPECT_NE(root.status().message().find("not a regular file"), std::string::npos)
      << root.status().message();
}

}  // namespace
}  // namespace hairrig
