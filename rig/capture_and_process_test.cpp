#include "rig/capture_and_process.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "rig/capture_test_util.h"
#include "rig/sim_rig.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using hairrig::testing::FreshDir;
using hairrig::testing::WriteSmallRig;

// The small rig is the simulated one (rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

TEST(CaptureAndProcess, ACaptureForASubjectGoesToItsFolder) {
  const std::string dir = FreshDir("capture_and_process");
  CaptureAndProcessOptions options;
  options.config_path = WriteSmallRig(dir);
  options.out_dir = dir + "/captures";
  options.subject = "Wig 03";
  int captured = 0;
  options.on_captured = [&](const CaptureSummary& s) {
    ++captured;
    EXPECT_EQ(s.status, "complete");
  };
  const auto summary = CaptureAndProcess(options);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(captured, 1);
  EXPECT_EQ(summary->capture.status, "complete") << summary->capture.message;
  EXPECT_EQ(fs::path(summary->capture.dir).filename(), "Wig_03");
  EXPECT_TRUE(fs::exists(dir + "/captures/Wig_03/manifest.json"));
  EXPECT_FALSE(summary->calibration.has_value());
  const nlohmann::json j = summary->ToJson();
  EXPECT_FALSE(j.contains("calibration"));
  EXPECT_EQ(j["views_completed"], summary->capture.views_completed);
  EXPECT_EQ(summary->BriefReport().rfind("capture " + summary->capture.dir + ": complete\n", 0), 0u)
      << summary->BriefReport();
}

// Checked before anything is written: an unsafe subject, and a rig without a
// calibration section when the capture is to be calibrated.
TEST(CaptureAndProcess, RefusesBeforeCapturing) {
  const std::string dir = FreshDir("capture_and_process_refused");
  CaptureAndProcessOptions options;
  options.config_path = WriteSmallRig(dir);
  options.out_dir = dir + "/captures";
  options.subject = "../x";
  EXPECT_EQ(CaptureAndProcess(options).status().code(), StatusCode::kInvalidArgument);
  options.subject.clear();
  options.calibrate = true;  // the small rig has no calibration section
  EXPECT_FALSE(CaptureAndProcess(options).ok());
  EXPECT_FALSE(fs::exists(options.out_dir));
}

TEST(CaptureAndProcess, OptionsThatNeedCalibrateAreNamed) {
  CaptureAndProcessOptions options;
  EXPECT_NE(options.Validate().message().find("out_dir"), std::string::npos);
  options.out_dir = "capture";
  options.intrinsics_files = {"camera.json"};
  EXPECT_EQ(options.Validate().message(), "--intrinsics needs --calibrate");
  options.intrinsics_files.clear();
  options.reconstruct = true;
  EXPECT_EQ(options.Validate().message(), "--reconstruct needs --calibrate");
  options.calibrate = true;
  EXPECT_TRUE(options.Validate().ok());
}

}  // namespace
}  // namespace hairrig
