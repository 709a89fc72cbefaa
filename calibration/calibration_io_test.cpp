#include "calibration/calibration_io.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// An intrinsics file as `hairrig calibrate-intrinsics` writes it, with `stddev`.
std::string WriteIntrinsics(const std::string& name, const std::array<double, CameraIntrinsics::kNumParams>& stddev) {
  ChArUcoCalibration result;
  result.intrinsics = {640, 480, 800, 800, 320, 240};
  result.stddev = stddev;
  result.rms_px = 0.2;
  const std::string path = (fs::temp_directory_path() / (name + "_" + std::to_string(getpid()) + ".json")).string();
  EXPECT_TRUE(WriteIntrinsicsFile(path, "CAM-1", "board.yaml", result).ok());
  return path;
}

TEST(CalibrationIo, IntrinsicsPriorsKeepTheirStandardDeviations) {
  const std::string path = WriteIntrinsics("priors_ok", {0.5, 0.5, 0.3, 0.3, 0.01, 0, 0, 0, 0});
  auto priors = ReadIntrinsicsPriors(path);
  fs::remove(path);
  ASSERT_TRUE(priors.ok()) << priors.status().ToString();
  ASSERT_EQ(priors->size(), 1u);
  EXPECT_EQ((*priors)[0].stddev[0], 0.5);
}

// A negative standard deviation used to read as "no prior" for that parameter.
TEST(CalibrationIo, ANegativeStandardDeviationIsRefusedNamingTheField) {
  const std::string path = WriteIntrinsics("priors_negative", {0.5, 0.5, -0.3, 0.3, 0, 0, 0, 0, 0});
  auto priors = ReadIntrinsicsPriors(path);
  fs::remove(path);
  ASSERT_FALSE(priors.ok());
  EXPECT_EQ(priors.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(priors.status().message().find("intrinsics_stddev.cx_px is -0.3"), std::string::npos)
      << priors.status().message();
}

}  // namespace
}  // namespace hairrig
