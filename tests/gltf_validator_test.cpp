// `hairrig export` checked by Khronos' glTF validator (the npm package that
// scripts/install-deps installs in tests/gltf_validator/): a small capture's
// strands with the mannequin's head and a 10-frame simulation with its
// guides and its strands' wisp ids, at both levels, the animation as frame
// nodes and as morph targets.
// Each file: no errors and no warnings, the vertex count and the animations
// the summary states, and each animation as long as its frames.
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

// Exports `dir` with its animation in `encoding`, validates both levels and
// checks them against the summary; the summary.
nlohmann::json ExportAndValidate(const std::string& dir, const std::string& encoding) {
  const auto exported = Hairrig("export " + dir + " --simulation " + dir +
                                "/simulation/head-shake --head etc/heads/mannequin.yaml "
                                "--display-strands 30 --animation-strands 30 "
                                "--display-cloud 100 --animation-encoding " +
                                encoding + " --out " + dir + "/" + encoding + ".glb --json");
  EXPECT_EQ(exported.exit_code, 0) << exported.output;
  const nlohmann::json summary = LastLineJson(exported.output);
  for (const char* level : {"full", "display"}) {
    const nlohmann::json& written = summary[level];
    const std::string path = written["path"];
    const auto validated =
        RunCommand("node " + std::string(kValidatorDir) + "/validate.mjs " + path);
    EXPECT_EQ(validated.exit_code, 0) << validated.output;
    const nlohmann::json report = LastLineJson(validated.output);
    SCOPED_TRACE(encoding + " " + level);
    EXPECT_EQ(report["errors"], 0) << report["issues"].dump(1);
    EXPECT_EQ(report["warnings"], 0) << report["issues"].dump(1);
    EXPECT_EQ(report["info"]["totalVertexCount"], written["vertices"]);
    // The full level animates the strands and the guides; the display level the strands.
    const bool full = std::string(level) == "full";
    EXPECT_EQ(report["info"]["animationCount"], full ? 2 : 1);
    EXPECT_EQ(written["frames"], full ? 20 : 10);
    // 10 frames at 10 fps: the last shown from 0.9 s to the animation's end at 1.0 s.
    const nlohmann::json doc = GlbJson(path);
    EXPECT_FALSE(doc.is_null()) << path;
    if (doc.is_null()) continue;
    for (const nlohmann::json& animation : doc["animations"]) {
      const int input = animation["samplers"][0]["input"];
      EXPECT_NEAR(doc["accessors"][input]["max"][0].get<double>(), 1.0, 1e-6);
      const bool morph = full && encoding == "morph";
      EXPECT_EQ(animation["channels"].size(), morph ? 1u : 10u);
    }
  }
  return summary;
}

TEST(GltfValidator, ExportedFilesAreValidAsWritten) {
  if (RunCommand("node --version").exit_code != 0)
    GTEST_SKIP() << "node is absent (scripts/install-deps --tests installs nodejs)";
  if (!fs::exists(std::string(kValidatorDir) + "/node_modules/gltf-validator"))
    GTEST_SKIP() << "gltf-validator is not installed in " << kValidatorDir
                 << " (scripts/install-deps --tests runs npm ci there)";
  const std::string dir = hairrig_test::MakeStrandCapture("gltf_validator", 10, /*guides=*/true);
  hairrig_test::AddPointsAndTruth(dir, 400);
  nlohmann::json clusters = nlohmann::json::array();
  for (int s = 0; s < 100; ++s) clusters.push_back(s % 7);  // the strands' wisps
  std::ofstream(dir + "/simulation/model.json") << nlohmann::json{{"cluster_of_strand", clusters}};
  const nlohmann::json nodes = ExportAndValidate(dir, "nodes");
  const nlohmann::json morph = ExportAndValidate(dir, "morph");
  // Every strand, the 25 animated and the 5 guides.
  EXPECT_EQ(nodes["full"]["strands"], 100 + 25 + 5);
  EXPECT_EQ(nodes["guides"], 5);
  EXPECT_EQ(nodes["wisps"], 7);
  // Every 4th of 100 (30 at most), the truth's every 2nd of 50, the 25 animated.
  EXPECT_EQ(nodes["display"]["strands"], 25 + 25 + 25);
  EXPECT_EQ(nodes["truth_strands"], 25);
  EXPECT_EQ(nodes["cloud_points"], 100);
  // Morph targets count one frame's vertices (frame nodes ten); the display
  // level is frame nodes either way.
  EXPECT_LT(morph["full"]["vertices"], nodes["full"]["vertices"]);
  EXPECT_EQ(morph["display"]["bytes"], nodes["display"]["bytes"]);
  EXPECT_EQ(morph["display"]["vertices"], nodes["display"]["vertices"]);
}

}  // namespace
