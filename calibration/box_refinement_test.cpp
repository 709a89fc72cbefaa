// The bundle adjustment's box refinement on synthetic detections: the default
// rig's two cameras and 19 stops seeing a box built off its drawing, the
// corners projected exactly and given 0.1 px of noise.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "calibration/calibration_evaluation.h"
#include "calibration/calibration_report.h"
#include "calibration/capture_calibration.h"
#include "core/calib_box.h"
#include "core/statistics.h"
#include "core/transform.h"

namespace hairrig {
namespace {

constexpr double kNoisePx = 0.1;
constexpr int kStops = 19;

const CameraIntrinsics kCameras[2] = {
    {1200, 1600, 1750, 1750, 602.5, 795.5, -0.03, 0.012, 0.0002, -0.0001, 0},
    {1200, 1600, 1760, 1758, 596.0, 803.0, -0.028, 0.01, -0.0001, 0.0002, 0}};

Rigid3d CamFromWorld(int camera) {
  return camera == 0 ? LookAt({900, 0, 700}, {0, 0, 390}) : LookAt({900, 0, 200}, {0, 0, 400});
}

Rigid3d TurntableFromBox() {
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(DegToRad(10.0), Eigen::Vector3d::UnitZ())),
                 Eigen::Vector3d(0, 0, 600));
}

struct SyntheticCapture {
  CaptureCalibrationInput input;
  std::vector<Rigid3d> true_cam_from_box;  // per frame
};

// The drawn box given to the calibration, the views showing `built`.
SyntheticCapture MakeCapture(const CalibBox& drawn, const CalibBox& built, uint64_t seed) {
  SyntheticCapture s;
  s.input.box = drawn;
  s.input.box_source = "etc/calib-box.yaml";
  s.input.box_height_mm = 600;
  s.input.box_yaw_deg = 10;
  for (int c = 0; c < 2; ++c) {
    CalibrationCamera camera;
    camera.name = camera.serial = c == 0 ? "upper" : "lower";
    camera.width_px = 1200, camera.height_px = 1600;
    camera.nominal = kCameras[c];
    s.input.cameras.push_back(camera);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoisePx);
  for (int stop = 0; stop < kStops; ++stop) {
    for (int c = 0; c < 2; ++c) {
      const double theta = 360.0 * stop / kStops;
      const Rigid3d cam_from_box = CamFromWorld(c) * WorldFromTurntable(theta) * TurntableFromBox();
      CalibrationFrame frame;
      frame.view = static_cast<int>(s.input.frames.size());
      frame.name = "view " + std::to_string(frame.view);
      frame.camera = c, frame.stop = stop, frame.turntable_deg = theta;
      ViewObservations seen;
      const Eigen::Vector3d eye_box = cam_from_box.Inverse().translation;
      for (const BoxTag& tag : built.tags) {
        const Eigen::Vector3d normal = built.faces[static_cast<size_t>(tag.face)].normal_box;
        if ((eye_box - tag.center_box_mm).normalized().dot(normal) < 0.3) continue;
        TagObservation o{tag.id, {}, drawn.FindTag(tag.id)->corners_box_mm};
        for (size_t k = 0; k < 4; ++k)
          o.corners_px[k] = Project(kCameras[c], cam_from_box * tag.corners_box_mm[k]) +
                            Eigen::Vector2d(noise(rng), noise(rng));
        seen.tags.push_back(o);
      }
      frame.observations = seen;
      s.input.frames.push_back(frame);
      s.true_cam_from_box.push_back(cam_from_box);
    }
  }
  return s;
}

CaptureCalibration Calibrate(const CaptureCalibrationInput& input, const BoxTolerance& tolerance) {
  CaptureCalibrationOptions options;
  options.fix_intrinsics = true;
  options.hard_prior = true;
  options.check_priors = false;
  options.box_tolerance = tolerance;
  auto result = CalibrateCapture(input, options);
  EXPECT_TRUE(result.ok()) << result.status().ToString();
  return result.ok() ? *result : CaptureCalibration{};
}

// Median camera-centre error (mm) in the frame of the true tags.
double MedianCentreErrorMm(const SyntheticCapture& s, const CaptureCalibration& result,
                           const CalibBox& built) {
  const Rigid3d estimated_from_truth =
      TruthFromEstimatedBox(result.box_as_built, built, TagsUsed(result)).Inverse();
  std::vector<double> errors;
  for (size_t f = 0; f < result.frames.size(); ++f) {
    if (!result.frames[f].solved) continue;
    const Rigid3d cam_from_true_box = result.frames[f].cam_from_box * estimated_from_truth;
    errors.push_back(
        (cam_from_true_box.Inverse().translation - s.true_cam_from_box[f].Inverse().translation)
            .norm());
  }
  return Median(std::move(errors));
}

class BoxRefinementTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto box = LoadCalibBox("etc/calib-box.yaml");
    ASSERT_TRUE(box.ok()) << box.status().ToString();
    drawn_ = *box;
  }
  CalibBox drawn_;
};

TEST_F(BoxRefinementTest, RecoversTheBoxAsBuiltAndTheCameras) {
  const CalibBox built = BuildBoxWithErrors(drawn_, {0.7, 1.0, 0.5, 0.3}, 11);
  const SyntheticCapture s = MakeCapture(drawn_, built, 1);
  const CaptureCalibration refined = Calibrate(s.input, kHandBuiltBoxTolerance);
  ASSERT_TRUE(refined.box_refined);
  const Rigid3d truth_from_estimated =
      TruthFromEstimatedBox(refined.box_as_built, built, TagsUsed(refined));
  ASSERT_FALSE(refined.tag_moves.empty());
  for (const TagRefinement& move : refined.tag_moves) {
    const Eigen::Vector3d centre =
        truth_from_estimated * refined.box_as_built.FindTag(move.id)->center_box_mm;
    EXPECT_LT((centre - built.FindTag(move.id)->center_box_mm).norm(), 0.15) << "tag " << move.id;
    EXPECT_GT(move.moved_sd_mm.x(), 0) << "tag " << move.id;
  }
  const CaptureCalibration exact = Calibrate(s.input, BoxTolerance{});
  EXPECT_FALSE(exact.box_refined);
  const double refined_error = MedianCentreErrorMm(s, refined, built);
  const double exact_error = MedianCentreErrorMm(s, exact, built);
  EXPECT_LT(refined_error, 0.2);
  EXPECT_GT(exact_error, 3 * refined_error);
  // The residuals with the box refined are the noise; with it taken as drawn, far above.
  EXPECT_NEAR(refined.residual_sigma_px, kNoisePx, 0.03);
  EXPECT_GT(refined.sigma_box_as_given_px, 3 * refined.sigma_box_refined_px);
  EXPECT_EQ(JudgeCalibration(s.input, refined).level, CalibrationVerdict::Level::kGood);
  const CalibrationVerdict verdict = JudgeCalibration(s.input, exact);
  EXPECT_EQ(verdict.level, CalibrationVerdict::Level::kCheck);
  std::string reasons;
  for (const std::string& reason : verdict.reasons) reasons += reason + "\n";
  EXPECT_NE(reasons.find("the box is not as etc/calib-box.yaml says"), std::string::npos)
      << reasons;
}

TEST_F(BoxRefinementTest, GaugeKeepsTheObservedTagsInPlaceOnAverage) {
  const CalibBox built = BuildBoxWithErrors(drawn_, {0.7, 1.0, 0.5, 0.3}, 12);
  const CaptureCalibration refined =
      Calibrate(MakeCapture(drawn_, built, 2).input, kHandBuiltBoxTolerance);
  ASSERT_TRUE(refined.box_refined);
  // The rigid fit of the refined corners onto the drawn ones is the identity.
  CalibBox observed_drawn = drawn_;
  observed_drawn.tags.clear();
  for (const TagRefinement& move : refined.tag_moves)
    observed_drawn.tags.push_back(*drawn_.FindTag(move.id));
  const Rigid3d drift = TruthFromEstimatedBox(refined.box_as_built, observed_drawn);
  EXPECT_LT(drift.translation.norm(), 2e-3);
  EXPECT_LT(RadToDeg(Eigen::AngleAxisd(drift.rotation).angle()), 2e-4);
}

TEST_F(BoxRefinementTest, NamesATagMovedFarBeyondTheTolerance) {
  CalibBox built = drawn_;
  for (BoxTag& tag : built.tags)
    if (tag.id == 5) tag.center_face_mm.x() += 5.0;
  PlaceTags(&built);
  const SyntheticCapture s = MakeCapture(drawn_, built, 3);
  const CaptureCalibration refined = Calibrate(s.input, kHandBuiltBoxTolerance);
  const CalibrationVerdict verdict = JudgeCalibration(s.input, refined);
  EXPECT_EQ(verdict.level, CalibrationVerdict::Level::kCheck);
  std::string named;
  for (const std::string& reason : verdict.reasons) {
    if (reason.find("tag ") == 0) named += reason + "\n";
  }
  EXPECT_NE(named.find("tag 5 moved"), std::string::npos) << named;
  EXPECT_EQ(named.find("tag 4 moved"), std::string::npos) << named;
}

TEST_F(BoxRefinementTest, AnExactBoxLosesNothingWhenRefined) {
  const SyntheticCapture s = MakeCapture(drawn_, drawn_, 4);
  const CaptureCalibration refined = Calibrate(s.input, kHandBuiltBoxTolerance);
  const CaptureCalibration exact = Calibrate(s.input, BoxTolerance{});
  EXPECT_LT(MedianCentreErrorMm(s, refined, drawn_),
            1.5 * MedianCentreErrorMm(s, exact, drawn_) + 0.01);
  EXPECT_LT(refined.sigma_box_as_given_px, 1.2 * refined.sigma_box_refined_px);
  EXPECT_EQ(JudgeCalibration(s.input, refined).level, CalibrationVerdict::Level::kGood);
  EXPECT_EQ(JudgeCalibration(s.input, exact).level, CalibrationVerdict::Level::kGood);
}

}  // namespace
}  // namespace hairrig
