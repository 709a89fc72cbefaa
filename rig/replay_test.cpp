#include "rig/replay.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/file_util.h"
#include "rig/capture.h"
#include "rig/capture_calibration_input.h"
#include "rig/replay_capture.h"
#include "sim_rig/sim_rig.h"
#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using namespace hairrig::testing;

// The recordings are made with the simulated rig (sim_rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

Result<CaptureSummary> Replay(const std::string& recorded, const std::string& out, double speed) {
  auto summary = ReplayCapture({.recorded_dir = recorded, .out_dir = out, .speed = speed});
  if (!summary.ok()) return summary.status();
  return summary->capture;
}

class ReplayTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = FreshDir("replay");
    // The head file lies beside the config, named by a relative path: the
    // replay must resolve it where the recording did, not in the capture folder.
    fs::create_directories(dir_ + "/heads");
    ASSERT_TRUE(WriteFileAtomic(dir_ + "/heads/ball.yaml",
                                "head:\n  center_mm: [0, 0, 250]\n  radii_mm: [70, 70, 90]\n")
                    .ok());
    CaptureOptions o;
    o.config_path = WriteSmallRig(dir_, {{"head", "head: heads/ball.yaml\n"}});
    o.out_dir = dir_ + "/recorded";
    auto s = RunCapture(o);
    ASSERT_TRUE(s.ok() && s->status == "complete");
  }
  static std::string dir_;
};
std::string ReplayTest::dir_;

TEST_F(ReplayTest, AReplayOfAReplayFindsTheFilesTheOriginalConfigNamed) {
  const std::string first = dir_ + "/replayed_once", second = dir_ + "/replayed_twice";
  auto once = Replay(dir_ + "/recorded", first, 0);
  ASSERT_TRUE(once.ok()) << once.status().ToString();
  auto twice = Replay(first, second, 0);
  ASSERT_TRUE(twice.ok()) << twice.status().ToString();
  EXPECT_EQ(twice->status, "complete") << twice->message;
  auto config = LoadCaptureRigConfig(second);
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  ASSERT_TRUE(config->head.has_value());
  EXPECT_DOUBLE_EQ(config->head->radii_mm.z(), 90);
}

TEST_F(ReplayTest, CaptureFromReplayHasTheSameChecksums) {
  for (double speed : {0.0, 1.0}) {
    const std::string out = dir_ + "/replayed_" + std::to_string(static_cast<int>(speed));
    auto s = Replay(dir_ + "/recorded", out, speed);
    ASSERT_TRUE(s.ok()) << s.status().ToString();
    EXPECT_EQ(s->status, "complete") << s->message;
    const auto original = VerifiedFramesOnDisk(dir_ + "/recorded");
    const auto replayed = VerifiedFramesOnDisk(out);
    ASSERT_EQ(replayed.size(), 38u);
    for (const auto& [view, r] : original) {
      EXPECT_EQ(replayed.at(view)["sha256"], r["sha256"]) << "view " << view;
      EXPECT_EQ(replayed.at(view)["angle_measured_deg"], r["angle_measured_deg"])
          << "view " << view;
    }
    std::printf("replay at speed %.0f: %.3f s for 38 views\n", speed, s->wall_s);
  }
}

TEST_F(ReplayTest, ReplayLeavesTheRecordingUntouchedAndSkipsUnverifiedFrames) {
  const std::string copy = dir_ + "/damaged";
  fs::copy(dir_ + "/recorded", copy, fs::copy_options::recursive);
  const auto journal_before = ReadFileBytes(copy + "/journal.jsonl");
  // A flipped byte in one frame: that frame no longer verifies and is not served.
  const std::string victim = copy + "/frames/005_SIM-CAM-LOWER.png";
  auto bytes = ReadFileBytes(victim);
  ASSERT_TRUE(bytes.ok());
  (*bytes)[bytes->size() / 2] ^= 0xff;
  ASSERT_TRUE(WriteFileAtomic(victim, bytes->data(), bytes->size()).ok());
  auto s = Replay(copy, dir_ + "/from_damaged", 0);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->status, "incomplete");
  EXPECT_EQ(s->missing_views, std::vector<int>{5});
  EXPECT_EQ(*ReadFileBytes(copy + "/journal.jsonl"), *journal_before);
}

// One angle shot under two light states: each replayed view gets its own frame.
TEST(Replay, SameAngleUnderTwoLightStates) {
  const std::string dir = FreshDir("replay_lights");
  CaptureOptions o;
  o.config_path =
      WriteSmallRig(dir, {{"plan",
                           "plan:\n  views:\n"
                           "    - {angle_deg: 30, camera: upper, lights: {top: 1, bottom: 0}}\n"
                           "    - {angle_deg: 30, camera: upper, lights: {top: 0, bottom: 1}}\n"}});
  o.out_dir = dir + "/recorded";
  auto recorded = RunCapture(o);
  ASSERT_TRUE(recorded.ok() && recorded->status == "complete");
  const auto original = VerifiedFramesOnDisk(o.out_dir);
  ASSERT_NE(original.at(0)["sha256"], original.at(1)["sha256"])
      << "the two light states should give different frames";
  auto s = Replay(o.out_dir, dir + "/replayed", 0);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->status, "complete") << s->message;
  const auto replayed = VerifiedFramesOnDisk(dir + "/replayed");
  for (int view : {0, 1})
    EXPECT_EQ(replayed.at(view)["sha256"], original.at(view)["sha256"]) << "view " << view;
}

TEST(Replay, RefusesAFolderThatIsNotACapture) {
  const std::string dir = FreshDir("replay_not_capture");
  auto s = OpenReplaySource(dir, {});
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("journal.jsonl"), std::string::npos) << s.status().ToString();
  EXPECT_FALSE(OpenReplaySource(dir, {.speed = -1}).ok());
}

}  // namespace
}  // namespace hairrig
