// `hairrig export` checked by Khronos' glTF validator (the npm package that
// scripts/install-deps installs in tests/gltf_validator/): a small capture's
// strands with the mannequin's head and a 10-frame simulation, at both
// levels. Each file: no errors and no warnings, the vertex count and the
// animation the summary states, and the animation as long as its frames.
// Skipped (exit 77) with the reason where node or the package is absent.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "tests/support/command_run.h"
#include "tests/support/strand_capture.h"

namespace {

namespace fs = std::filesystem;
using hairrig_test::Hairrig;
using hairrig_test::LastLineJson;
using hairrig_test::RunCommand;

constexpr const char* kValidatorDir = "tests/gltf_validator";

// The JSON chunk of a GLB file.
nlohmann::json GlbJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  uint32_t length = 0;
  if (bytes.size() < 20) return nullptr;
  std::memcpy(&length, bytes.data() + 12, 4);
  if (bytes.size() < 20 + static_cast<size_t>(length)) return nullptr;
  return nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + length);
}

TEST(GltfValidator, ExportedFilesAreValidAsWritten) {
  if (RunCommand("node --version").exit_code != 0)
    GTEST_SKIP() << "node is absent (scripts/install-deps --tests installs nodejs)";
  if (!fs::exists(std::string(kValidatorDir) + "/node_modules/gltf-validator"))
    GTEST_SKIP() << "gltf-validator is not installed in " << kValidatorDir
                 << " (scripts/install-deps --tests runs npm ci there)";
  const std::string dir = hairrig_test::MakeStrandCapture("gltf_validator", 10);
  hairrig_test::AddPointsAndTruth(dir, 400);
  const auto exported = Hairrig("export " + dir + " --simulation " + dir +
                                "/simulation/head-shake --head etc/heads/mannequin.yaml "
                                "--display-strands 30 --animation-strands 30 "
                                "--display-cloud 100 --json");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const nlohmann::json summary = LastLineJson(exported.output);
  for (const char* level : {"full", "display"}) {
    const nlohmann::json& written = summary[level];
    const std::string path = written["path"];
    const auto validated =
        RunCommand("node " + std::string(kValidatorDir) + "/validate.mjs " + path);
    ASSERT_EQ(validated.exit_code, 0) << validated.output;
    const nlohmann::json report = LastLineJson(validated.output);
    EXPECT_EQ(report["errors"], 0) << report["issues"].dump(1);
    EXPECT_EQ(report["warnings"], 0) << report["issues"].dump(1);
    EXPECT_EQ(report["info"]["totalVertexCount"], written["vertices"]) << level;
    EXPECT_EQ(report["info"]["animationCount"], 1) << level;
    EXPECT_EQ(written["frames"], 10) << level;
    // 10 frames at 10 fps: the last shown from 0.9 s to the animation's end at 1.0 s.
    const nlohmann::json doc = GlbJson(path);
    ASSERT_FALSE(doc.is_null()) << path;
    const int input = doc["animations"][0]["samplers"][0]["input"];
    EXPECT_NEAR(doc["accessors"][input]["max"][0].get<double>(), 1.0, 1e-6) << level;
    EXPECT_EQ(doc["animations"][0]["channels"].size(), 10u) << level;
  }
  EXPECT_EQ(summary["full"]["strands"], 100 + 25);  // every strand, and the 25 animated
  // Every 4th of 100 (30 at most), the truth's every 2nd of 50, the 25 animated.
  EXPECT_EQ(summary["display"]["strands"], 25 + 25 + 25);
  EXPECT_EQ(summary["truth_strands"], 25);
  EXPECT_EQ(summary["cloud_points"], 100);
}

}  // namespace
