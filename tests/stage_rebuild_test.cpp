// `hairrig stage` skips a stage only for the build that ran it: a copy of the
// hairrig binary skips what the original ran, a copy whose bytes differ (a
// rebuild under the same version) runs the stage again.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

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

// The binary copied to `path`, with `extra` bytes appended (an ELF file runs
// the same with bytes after its last section).
std::string CopyOfHairrig(const std::string& path, const std::string& extra) {
  fs::create_directories(fs::path(path).parent_path());
  fs::copy_file(HAIRRIG_BIN, path, fs::copy_options::overwrite_existing);
  std::ofstream(path, std::ios::app | std::ios::binary) << extra;
  fs::permissions(path, fs::perms::owner_exec, fs::perm_options::add);
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
  const std::string same = CopyOfHairrig(work + "/same/hairrig", "");
  const std::string rebuilt = CopyOfHairrig(work + "/rebuilt/hairrig", "another build");

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
}

}  // namespace
