#include "calibration/calibration_evaluation.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "tests/support/calibration_documents.h"

namespace hairrig {
namespace {

constexpr double kRotationErrorDeg = 1.0;

// The truth of views 0 and 1: the camera 500 mm in front of the box.
CaptureTruth SmallTruth() {
  CaptureTruth truth;
  for (int v : {0, 1}) {
    truth.views[v] = {"CAM-UPPER", hairrig_test::SmallTestIntrinsics(),
                      Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 500))};
  }
  return truth;
}

// One tag (id 4) of 40 mm on the box face z = 0, centred on the box origin.
CalibBox OneTagBox() {
  CalibBox box;
  BoxTag tag;
  tag.id = 4;
  tag.corners_box_mm = {Eigen::Vector3d(-20, -20, 0), Eigen::Vector3d(20, -20, 0),
                        Eigen::Vector3d(20, 20, 0), Eigen::Vector3d(-20, 20, 0)};
  box.tags.push_back(tag);
  return box;
}

// View 0 solved, its rotation 1 deg off about the optical axis, its focal
// length 1 % long, its detections 0.5 px from the true corners; view 1 failed.
StoredCalibration SmallCalibration(const CaptureTruth& truth, const CalibBox& box) {
  StoredCalibration calibration;
  calibration.mode = "turntable";
  calibration.rms_px = 0.25;
  StoredCalibration::Camera camera;
  camera.serial = "CAM-UPPER";
  camera.solved = true;
  camera.intrinsics = camera.initial = hairrig_test::SmallTestIntrinsics();
  camera.intrinsics.fx_px *= 1.01;
  camera.intrinsics_source = "views";
  calibration.cameras.push_back(camera);
  const Rigid3d& true_pose = truth.views.at(0).cam_from_box;
  StoredCalibration::View solved;
  solved.view = 0;
  solved.solved = true;
  solved.rms_px = 0.25;
  solved.cam_from_box = solved.cam_from_box_initial = Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(DegToRad(kRotationErrorDeg), Eigen::Vector3d::UnitZ())),
      true_pose.translation);
  StoredCalibration::Tag tag;
  tag.id = 4;
  for (size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d truth_px =
        Project(truth.views.at(0).intrinsics, true_pose * box.tags[0].corners_box_mm[k]);
    tag.corners_px[k] = truth_px + Eigen::Vector2d(0.3, 0.4);
  }
  solved.tags.push_back(tag);
  StoredCalibration::View failed;
  failed.view = 1;
  calibration.views = {solved, failed};
  return calibration;
}

TEST(CalibrationEvaluation, ErrorsOfASmallCalibrationAgainstItsTruth) {
  const CaptureTruth truth = SmallTruth();
  const CalibBox box = OneTagBox();
  const auto e = EvaluateCalibration(SmallCalibration(truth, box), truth, {box, box});
  ASSERT_TRUE(e.ok()) << e.status().ToString();
  EXPECT_EQ(e->views, 2);
  EXPECT_EQ(e->views_compared, 1);
  ASSERT_EQ(e->solved.rotation_deg.values.size(), 1u);
  EXPECT_NEAR(e->solved.rotation_deg.values[0], kRotationErrorDeg, 1e-9);
  EXPECT_NEAR(e->solved.camera_centre_mm.values[0], 0,
              1e-9);  // a turn about the axis through the camera
  EXPECT_NEAR(e->solved.focal_percent.values.at(0), 1.0, 1e-9);
  EXPECT_NEAR(e->initial.focal_percent.values.at(0), 0.0, 1e-12);
  ASSERT_TRUE(e->corner_noise_px.has_value());
  EXPECT_NEAR(*e->corner_noise_px, 0.5, 1e-9);
  EXPECT_EQ(e->initial_source, "Zhang per camera + per-view IPPE");

  const nlohmann::json j = e->ToJson();
  EXPECT_EQ(j["stage"], "calibration");
  EXPECT_NEAR(j["rms_over_corner_noise"].get<double>(), 0.5, 1e-9);
  EXPECT_TRUE(j["solved"].contains("reprojection_rms_px"));
  EXPECT_FALSE(j["initial"].contains("reprojection_rms_px"));
  EXPECT_EQ(j["uncertainty"], nlohmann::json({{"views", 0}}));  // no covariance in this calibration
  const std::string brief = e->BriefReport();
  EXPECT_NE(brief.find("1 of 2 views"), std::string::npos) << brief;
  EXPECT_NE(brief.find("against corner noise 0.5000 px"), std::string::npos) << brief;
}

TEST(CalibrationEvaluation, PosesAreComparedInTheTrueTagsFrame) {
  // The calibration's box has its tag 2 mm along x from where the images show
  // it; its pose is exact in that box's frame, 2 mm off in the true one.
  const CaptureTruth truth = SmallTruth();
  const CalibBox true_box = OneTagBox();
  CalibBox estimated_box = true_box;
  const Eigen::Vector3d shift(2, 0, 0);
  for (Eigen::Vector3d& corner : estimated_box.tags[0].corners_box_mm) corner += shift;
  StoredCalibration calibration = SmallCalibration(truth, true_box);
  calibration.views[0].cam_from_box =
      truth.views.at(0).cam_from_box * Rigid3d(Eigen::Quaterniond::Identity(), -shift);

  const auto aligned = EvaluateCalibration(calibration, truth, {estimated_box, true_box});
  ASSERT_TRUE(aligned.ok()) << aligned.status().ToString();
  EXPECT_NEAR(aligned->solved.camera_centre_mm.values.at(0), 0, 1e-9);
  EXPECT_NEAR(aligned->solved.rotation_deg.values.at(0), 0, 1e-6);
  EXPECT_NEAR(aligned->box_alignment_mm, 2, 1e-9);
  EXPECT_NE(aligned->BriefReport().find("true tags' frame"), std::string::npos);

  const auto unaligned = EvaluateCalibration(calibration, truth, {true_box, true_box});
  ASSERT_TRUE(unaligned.ok());
  EXPECT_NEAR(unaligned->solved.camera_centre_mm.values.at(0), 2, 1e-9);
  EXPECT_EQ(unaligned->BriefReport().find("true tags' frame"), std::string::npos);
}

TEST(CalibrationEvaluation, BoxesWithNoTagInCommonAreAnError) {
  const CaptureTruth truth = SmallTruth();
  const CalibBox true_box = OneTagBox();
  CalibBox other_box = true_box;
  other_box.tags[0].id = 7;
  const auto e =
      EvaluateCalibration(SmallCalibration(truth, true_box), truth, {other_box, true_box});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(e.status().message().find("no tag in common"), std::string::npos);
}

TEST(CalibrationEvaluation, NoSolvedViewInTheTruthIsAnError) {
  CaptureTruth truth = SmallTruth();
  const CalibBox box = OneTagBox();
  const StoredCalibration calibration = SmallCalibration(truth, box);
  truth.views.erase(0);
  const auto e = EvaluateCalibration(calibration, truth, {box, box});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kFailedPrecondition);
}

// A calibrate-intrinsics result and the truth `sim charuco` writes, in a fresh folder.
std::string IntrinsicsFolder(const std::string& name, const nlohmann::json& truth) {
  const std::string dir = ::testing::TempDir() + "/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  nlohmann::json solved = hairrig_test::IntrinsicsDocument();  // fx stddev 0.5 px
  solved["intrinsics"]["fx_px"] = 808;
  EXPECT_TRUE(WriteFileAtomic(dir + "/intrinsics.json", solved.dump()).ok());
  EXPECT_TRUE(WriteFileAtomic(dir + "/ground_truth.json", truth.dump()).ok());
  return dir;
}

TEST(IntrinsicsEvaluation, ErrorsInStandardDeviations) {
  const nlohmann::json truth{{"format", "hairrig-charuco-truth"},
                             {"version", 1},
                             {"serial", "CAM-UPPER"},
                             {"intrinsics", IntrinsicsToJson(hairrig_test::SmallTestIntrinsics())}};
  const std::string dir = IntrinsicsFolder("intrinsics_eval", truth);
  const auto e = EvaluateIntrinsicsFolder({.dir = dir});
  ASSERT_TRUE(e.ok()) << e.status().ToString();
  EXPECT_EQ(e->serial, "CAM-UPPER");
  EXPECT_NEAR(e->focal_percent, 1.0, 1e-9);
  EXPECT_NEAR(e->principal_point_px, 0, 1e-12);
  EXPECT_NEAR(e->worst_error_in_stddev, 16, 1e-9);  // 8 px at 0.5 px
  EXPECT_NEAR(e->ToJson()["params"]["fx_px"]["error_in_stddev"].get<double>(), 16, 1e-9);
  // The parameters by name, as the JSON object lists them.
  const std::string brief = e->BriefReport();
  EXPECT_LT(brief.find("  cx_px "), brief.find("  fx_px ")) << brief;
  EXPECT_LT(brief.find("  k3 "), brief.find("  p1 ")) << brief;
}

TEST(IntrinsicsEvaluation, AnotherFileAsTruthIsRefused) {
  const std::string dir =
      IntrinsicsFolder("intrinsics_eval_bad", hairrig_test::IntrinsicsDocument());
  const auto e = EvaluateIntrinsicsFolder({.dir = dir});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(e.status().message().find("hairrig-charuco-truth"), std::string::npos)
      << e.status().ToString();
  EXPECT_FALSE(EvaluateIntrinsicsFolder({}).ok());
}

}  // namespace
}  // namespace hairrig
