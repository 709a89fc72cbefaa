// `hairrig stage` skips a stage only for the build that ran it: a copy of the
// hairrig binary skips what the original ran, a copy with another build ID (a
// rebuild under the same version) runs the stage again.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/strand_io.h"
#include "tests/support/command_run.h"

namespace {

namespace fs = std::filesystem;
using hairrig_test::LastLineJson;
using hairrig_test::RunCommand;

// A capture folder holding what the fit stage reads: a few straight strands.
std::string StrandsCapture(const std::string& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir + "/reconstruction/strands");
  hairrig::StrandSet set;
  for (int s = 0; s < 6; ++s) {
    std::vector<Eigen::Vector3f> points;
    for (int k = 0; k < 40; ++k)
      points.emplace_back(15.0f * static_cast<float>(s), 0.0f, -2.0f * static_cast<float>(k));
    set.AddStrand(points);
  }
  EXPECT_TRUE(hairrig::WriteStrands(dir + "/reconstruction/strands/strands.ply", set).ok());
  return dir;
}

// The binary copied to `path`; with `other_build`, one byte of its GNU build
// ID (which `hairrig --version` prints) changed, as a rebuild changes it.
std::string CopyOfHairrig(const std::string& path, bool other_build) {
  fs::create_directories(fs::path(path).parent_path());
  std::ifstream in(HAIRRIG_BIN, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (other_build) {
    const std::string version = RunCommand(std::string(HAIRRIG_BIN) + " --version").output;
    const size_t at = version.find("(build ");
    EXPECT_NE(at, std::string::npos) << version;
    const std::string hex = version.substr(at + 7, version.find(')', at) - at - 7);
    EXPECT_EQ(hex.size(), 40u) << "not a GNU build ID: " << hex;
    std::string id;
    for (size_t k = 0; k + 1 < hex.size(); k += 2)
      id += static_cast<char>(std::stoi(hex.substr(k, 2), nullptr, 16));
    const size_t note = bytes.find(id);
    EXPECT_NE(note, std::string::npos) << "the build ID is not in the file";
    if (note != std::string::npos) bytes[note] = static_cast<char>(bytes[note] ^ 1);
  }
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  fs::permissions(path, fs::perms::owner_all);
  return path;
}

// The fit stage of `capture` by `binary`, with two guides (the options file
// beside the capture).
nlohmann::json FitStage(const std::string& binary, const std::string& capture) {
  const std::string options = capture + "_options.json";
  std::ofstream(options) << R"({"fit": {"guides": 2, "threads": 1}})";
  const hairrig_test::CommandRun run =
      RunCommand(binary + " --log-level warning stage fit --capture " + capture + " --options " +
                 options + " --json");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  return run.exit_code == 0 ? LastLineJson(run.output) : nlohmann::json::object();
}

TEST(StageRebuild, AnotherBuildOfTheSameVersionRunsTheStageAgain) {
  const std::string work = ::testing::TempDir() + "/stage_rebuild";
  const std::string capture = StrandsCapture(work + "/capture");
  const std::string same = CopyOfHairrig(work + "/same/hairrig", false);
  const std::string rebuilt = CopyOfHairrig(work + "/rebuilt/hairrig", true);

  const nlohmann::json first = FitStage(HAIRRIG_BIN, capture);
  EXPECT_FALSE(first.value("skipped", true)) << first.dump();
  const nlohmann::json by_copy = FitStage(same, capture);
  EXPECT_TRUE(by_copy.value("skipped", false)) << by_copy.dump();
  EXPECT_EQ(by_copy.value("input_hash", ""), first.value("input_hash", "x"));

  const nlohmann::json by_rebuilt = FitStage(rebuilt, capture);
  EXPECT_FALSE(by_rebuilt.value("skipped", true)) << by_rebuilt.dump();
  EXPECT_NE(by_rebuilt.value("input_hash", ""), first.value("input_hash", ""));
  const nlohmann::json again = FitStage(rebuilt, capture);
  EXPECT_TRUE(again.value("skipped", false)) << again.dump();
  fs::remove_all(work + "/same");  // two copies of the binary
  fs::remove_all(work + "/rebuilt");
}

}  // namespace
