#include "calibration/calibration_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>

#include "core/charuco_board.h"
#include "core/file_util.h"
#include "core/geometry_json.h"
#include "tests/support/calibration_documents.h"
#include "tests/support/synthetic_calibration.h"

namespace hairrig {
namespace {

using nlohmann::json;

std::string Write(const std::string& name, const json& j) {
  const std::string path = ::testing::TempDir() + "/" + name;
  EXPECT_TRUE(WriteFileAtomic(path, j.dump()).ok());
  return path;
}

TEST(CalibrationIo, ReadsWhatItWrites) {
  const auto priors =
      ReadIntrinsicsPriors(Write("intrinsics.json", hairrig_test::IntrinsicsDocument()));
  ASSERT_TRUE(priors.ok()) << priors.status().ToString();
  ASSERT_EQ(priors->size(), 1u);
  EXPECT_EQ(priors->at(0).serial, "CAM-UPPER");
  EXPECT_EQ(priors->at(0).stddev[0], 0.5);
  const auto calibration =
      ReadCalibration(Write("calibration.json", hairrig_test::CalibrationDocument()));
  ASSERT_TRUE(calibration.ok()) << calibration.status().ToString();
  ASSERT_EQ(calibration->views.size(), 2u);  // a solved and a failed view
  EXPECT_EQ(calibration->views[0].tags.at(0).corners_px[3].y(), 8);
}

// Each damaged file gives CorruptData naming the file and the field (a
// numeric serial used to end in std::terminate; a negative standard deviation
// was accepted).
TEST(CalibrationIo, DamagedIntrinsicsFilesNameTheField) {
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[](json& j) { j["serial"] = 5; }, "field 'serial': expected a string"},
      {[](json& j) { j["serial"] = ""; }, "field 'serial': is empty"},
      {[](json& j) { j["intrinsics_stddev"]["fx_px"] = -0.5; }, "field 'intrinsics_stddev.fx_px'"},
      {[](json& j) { j["intrinsics"]["fx_px"] = "x"; }, "field 'intrinsics': fx_px"},
      {[](json& j) { j["version"] = "1"; }, "field 'version'"},
      {[](json& j) { j = json::array(); }, "expected an object"},
  };
  for (const auto& [damage, expected] : cases) {
    json j = hairrig_test::IntrinsicsDocument();
    damage(j);
    const std::string path = Write("damaged_intrinsics.json", j);
    const auto priors = ReadIntrinsicsPriors(path);
    ASSERT_FALSE(priors.ok()) << j.dump();
    EXPECT_EQ(priors.status().code(), StatusCode::kCorruptData);
    EXPECT_NE(priors.status().message().find(path + ": " + expected), std::string::npos)
        << priors.status().ToString();
  }
}

TEST(CalibrationIo, DamagedCalibrationFilesNameTheField) {
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[](json& j) { j["views"][0]["camera"] = 1; },
       "field 'views[0].camera': expected an integer in [0, 0]"},
      {[](json& j) { j["views"][0]["view"] = 2.5; }, "field 'views[0].view'"},
      {[](json& j) { j["views"][0]["tags"][0]["corners_px"][2] = {1}; },
       "field 'views[0].tags[0].corners_px'"},
      {[](json& j) { j["views"][0]["cam_from_box"] = "identity"; },
       "field 'views[0].cam_from_box'"},
      {[](json& j) { j["cameras"][0]["name"] = json::array(); }, "field 'cameras[0].name'"},
      {[](json& j) {
         j["cameras"][0]["intrinsics_stddev"] = {{"k1", -1}};
       },
       "field 'cameras[0].intrinsics_stddev.k1'"},
      {[](json& j) { j["views"] = 3; }, "field 'views': expected a list"},
  };
  for (const auto& [damage, expected] : cases) {
    json j = hairrig_test::CalibrationDocument();
    damage(j);
    const std::string path = Write("damaged_calibration.json", j);
    const auto calibration = ReadCalibration(path);
    ASSERT_FALSE(calibration.ok()) << j.dump();
    EXPECT_EQ(calibration.status().code(), StatusCode::kCorruptData);
    EXPECT_NE(calibration.status().message().find(path + ": " + expected), std::string::npos)
        << calibration.status().ToString();
  }
}

namespace fs = std::filesystem;

// An intrinsics file as `hairrig calibrate-intrinsics` writes it, with `stddev`.
std::string WriteIntrinsics(const std::string& name,
                            const std::array<double, CameraIntrinsics::kNumParams>& stddev) {
  ChArUcoCalibration result;
  result.intrinsics = {640, 480, 800, 800, 320, 240};
  result.stddev = stddev;
  result.rms_px = 0.2;
  const std::string path =
      (fs::temp_directory_path() / (name + "_" + std::to_string(getpid()) + ".json")).string();
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

// A negative standard deviation is refused (it would drop that parameter's prior).
TEST(CalibrationIo, ANegativeStandardDeviationIsRefusedNamingTheField) {
  const std::string path = WriteIntrinsics("priors_negative", {0.5, 0.5, -0.3, 0.3, 0, 0, 0, 0, 0});
  auto priors = ReadIntrinsicsPriors(path);
  fs::remove(path);
  ASSERT_FALSE(priors.ok());
  EXPECT_EQ(priors.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(priors.status().message().find("cx_px"), std::string::npos)
      << priors.status().message();
}

// mrcal's corners cache: every corner of the board for each used image, in id
// order, "- - -" where a corner was not detected; unused images left out.
TEST(CalibrationIo, MrcalCornersListEveryBoardCornerOfTheUsedImages) {
  auto board = MakeChArUcoBoard("DICT_5X5_100", 4, 3, 30, 22);  // 3 x 2 inner corners
  ASSERT_TRUE(board.ok()) << board.status().ToString();
  ASSERT_EQ(board->corners_board_mm.size(), 6u);
  ChArUcoCalibration result;
  ChArUcoImage used;
  used.path = "/somewhere/view_000.png";
  used.used = true;
  used.detected.ids = {4, 1};
  used.detected.corners_px = {Eigen::Vector2d(10.25, 20.5), Eigen::Vector2d(1, 2.125)};
  ChArUcoImage unused = used;
  unused.path = "/somewhere/view_001.png";
  unused.used = false;
  result.images = {used, unused};
  const std::string path = ::testing::TempDir() + "/corners.vnl";
  ASSERT_TRUE(WriteMrcalCorners(path, *board, result).ok());
  const auto text = ReadFileText(path, 1 << 20);
  fs::remove(path);
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  EXPECT_EQ(*text,
            "# filename x y level\n"
            "view_000.png - - -\n"
            "view_000.png 1.0000 2.1250 0\n"
            "view_000.png - - -\n"
            "view_000.png - - -\n"
            "view_000.png 10.2500 20.5000 0\n"
            "view_000.png - - -\n");
}

// Each camera's opencv/<serial>.yaml, read by OpenCV's own cv::FileStorage,
// holds the solved intrinsics: the image size, the camera matrix and the
// distortion coefficients in OpenCV's order (k1 k2 p1 p2 k3), to the last
// digit the text keeps.
TEST(CalibrationIo, OpenCvYamlReadsBackWithFileStorage) {
  const hairrig_test::SyntheticCalibration s = hairrig_test::MakeSyntheticCalibration();
  const fs::path dir = fs::path(::testing::TempDir()) / ("opencv_yaml_" + std::to_string(getpid()));
  ASSERT_TRUE(WriteCalibration(dir.string(), s.input, s.result).ok());
  for (size_t c = 0; c < s.input.cameras.size(); ++c) {
    const std::string path = (dir / "opencv" / (s.input.cameras[c].serial + ".yaml")).string();
    const cv::FileStorage yaml(path, cv::FileStorage::READ);
    ASSERT_TRUE(yaml.isOpened()) << path;
    const CameraIntrinsics& k = s.result.cameras[c].intrinsics;
    EXPECT_EQ(static_cast<int>(yaml["image_width"]), k.width_px) << path;
    EXPECT_EQ(static_cast<int>(yaml["image_height"]), k.height_px) << path;
    cv::Mat matrix, distortion;
    yaml["camera_matrix"] >> matrix;
    yaml["distortion_coefficients"] >> distortion;
    ASSERT_EQ(matrix.type(), CV_64F) << path;
    ASSERT_EQ(distortion.type(), CV_64F) << path;
    ASSERT_EQ(matrix.rows * matrix.cols, 9) << path;
    ASSERT_EQ(distortion.rows * distortion.cols, 5) << path;
    const double expected_matrix[9] = {k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1};
    const double expected_distortion[5] = {k.k1, k.k2, k.p1, k.p2, k.k3};
    for (int i = 0; i < 9; ++i) {
      const double tolerance = 1e-15 * std::abs(expected_matrix[i]);
      EXPECT_NEAR(matrix.at<double>(i / 3, i % 3), expected_matrix[i], tolerance)
          << path << " camera_matrix[" << i << "]";
    }
    for (int i = 0; i < 5; ++i) {
      const double tolerance = 1e-15 * std::abs(expected_distortion[i]);
      EXPECT_NEAR(distortion.at<double>(i), expected_distortion[i], tolerance)
          << path << " distortion_coefficients[" << i << "]";
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hairrig
