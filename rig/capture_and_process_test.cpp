#include "rig/capture_and_process.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/calibrate_capture.h"
#include "rig/capture.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture_dataset.h"
#include "rig/device_check.h"
#include "rig/reconstruct_capture.h"
#include "rig/replay.h"
#include "rig/rig_config.h"
#include "sim_hw/quota_storage.h"
#include "sim_rig/sim_rig.h"
#include "tests/support/capture_test_util.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using hairrig::testing::FreshDir;
using hairrig::testing::WriteSmallRig;

// The small rig is the simulated one (sim_rig/sim_rig.h).
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

// The calibration's files honour storage.min_free_mb as the capture's do: on
// a disk that another program filled once the capture completed, the
// calibration is not run. The capture stays complete, as its manifest.json
// says; the summary's calibration_skipped (exit code 3) says why and how to
// calibrate once there is room.
TEST(CaptureAndProcess, NoRoomForTheCalibrationAboveMinFreeSkipsItAndKeepsTheCapture) {
  const std::string dir = FreshDir("capture_and_process_no_room");
  CaptureAndProcessOptions options;
  options.config_path = WriteSmallRig(
      dir, {{"calibration", "calibration:\n  box: " + fs::absolute("etc/calib-box.yaml").string() +
                                "\n  box_height_mm: 600\n  box_yaw_deg: 10\n"}});
  auto config = LoadRigConfig(options.config_path);
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok()) << rig.status().ToString();
  auto disk = std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = 1'000'000'000});
  (*rig)->capture_storage = disk;
  options.rig = rig->get();
  options.out_dir = dir + "/c";
  options.calibrate = true;
  const uint64_t min_free = 10'000'000;  // the small rig's storage.min_free_mb
  options.on_captured = [&](const CaptureSummary& s) {
    ASSERT_EQ(s.status, "complete") << s.message;
    const auto free = disk->FreeBytes(s.dir);
    ASSERT_TRUE(free.ok());
    disk->Consume(*free - (min_free + 100'000));
  };
  const auto summary = CaptureAndProcess(options);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->capture.status, "complete") << summary->capture.message;
  const nlohmann::json j = summary->ToJson();
  EXPECT_EQ(j["status"], "complete");
  std::ifstream manifest(summary->capture.dir + "/manifest.json");
  EXPECT_EQ(nlohmann::json::parse(manifest)["status"], "complete");
  ASSERT_TRUE(summary->calibration_skipped.has_value());
  const std::string& reason = summary->calibration_skipped->reason;
  EXPECT_NE(reason.find("storage.min_free_mb"), std::string::npos) << reason;
  const std::string& action = summary->calibration_skipped->action;
  EXPECT_NE(action.find("free space"), std::string::npos) << action;
  EXPECT_NE(action.find("hairrig calibrate " + summary->capture.dir), std::string::npos) << action;
  EXPECT_EQ(j["calibration_skipped"]["reason"], reason);
  EXPECT_EQ(j["calibration_skipped"]["action"], action);
  EXPECT_NE(summary->BriefReport().find("calibration not run: "), std::string::npos)
      << summary->BriefReport();
  EXPECT_FALSE(summary->calibration.has_value());
  EXPECT_FALSE(fs::exists(summary->capture.dir + "/calibration"));
}

TEST(CaptureAndProcess, OptionsThatNeedCalibrateAreNamed) {
  CaptureAndProcessOptions options;
  EXPECT_NE(options.Check().message().find("out_dir"), std::string::npos);
  options.out_dir = "capture";
  options.intrinsics_files = {"camera.json"};
  EXPECT_EQ(options.Check().message(), "--intrinsics needs --calibrate");
  options.intrinsics_files.clear();
  options.reconstruct = true;
  EXPECT_EQ(options.Check().message(), "--reconstruct needs --calibrate");
  options.calibrate = true;
  EXPECT_TRUE(options.Check().ok());
}

// The rig's options refuse a bad value with InvalidArgument naming the field;
// a nested struct's field is named after the field holding it.
TEST(RigOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(CalibrateFolderOptions{}.Check().ok());
  EXPECT_TRUE(DatasetOptions{}.Check().ok());
  EXPECT_TRUE(ReplayOptions{}.Check().ok());
  EXPECT_TRUE(DeviceCheckOptions{}.Check().ok());
  EXPECT_TRUE(RigBuildOptions{}.Check().ok());
  {
    CalibrateFolderOptions o;
    o.calibration.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "calibration: threads"));
    o = CalibrateFolderOptions{};
    o.calibration.detector.max_hamming = 7;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "calibration: detector: max_hamming"));
    o = CalibrateFolderOptions{};
    o.prior_files = {"a.json", ""};
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "prior_files[1]"));
  }
  {
    CaptureOptions o;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "--out"));
    o.out_dir = "capture";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
  }
  {
    DatasetOptions o;
    o.png_compression = 10;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "png_compression"));
  }
  {
    ReplayOptions o;
    o.speed = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "speed"));
    o.speed = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "speed"));
  }
  {
    ReconstructCaptureOptions o;
    o.dir = "capture";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.points.fusion.max_cost = 2;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "points: fusion: fusion max_cost"));
    o.stage = ReconstructStage::kStrands;
    EXPECT_TRUE(o.Check().ok()) << "the points' options are not used by the strands stage";
    o.strands.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "strands: threads"));
  }
}

// The entry points taking the options refuse bad ones before any work.
TEST(RigOptions, EntryPointsCheckTheirOptions) {
  const std::string dir = FreshDir("rig_options");
  const std::string dataset_dir = dir + "/dataset";
  DatasetOptions dataset;
  dataset.png_compression = -1;
  const auto created = CaptureDataset::Create(dataset_dir, "", {}, dataset);
  ASSERT_FALSE(created.ok());
  EXPECT_NE(created.status().message().find("png_compression"), std::string::npos);
  EXPECT_FALSE(fs::exists(dataset_dir)) << "nothing is made for bad options";

  const auto source = OpenReplaySource(dir, {.speed = -2.0});
  ASSERT_FALSE(source.ok());
  EXPECT_NE(source.status().message().find("speed"), std::string::npos);

  const auto captured = RunCapture(CaptureOptions{});
  ASSERT_FALSE(captured.ok());
  EXPECT_NE(captured.status().message().find("--out"), std::string::npos);

  CalibrateFolderOptions calibrate;
  calibrate.calibration.huber_px = 0;
  const auto calibrated = CalibrateCaptureFolder(dir + "/no_capture", calibrate);
  ASSERT_FALSE(calibrated.ok());
  EXPECT_EQ(calibrated.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(calibrated.status().message().find("calibration: huber_px"), std::string::npos)
      << calibrated.status().ToString();

  ReconstructCaptureOptions reconstruct;
  reconstruct.dir = dir + "/no_capture";
  reconstruct.points.segmentation.work_scale = 0;
  const auto reconstructed = ReconstructCapture(reconstruct);
  ASSERT_FALSE(reconstructed.ok());
  EXPECT_NE(reconstructed.status().message().find("points: segmentation"), std::string::npos)
      << reconstructed.status().ToString();
}

}  // namespace
}  // namespace hairrig
