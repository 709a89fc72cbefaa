// The calibration's stated uncertainty can be trusted: over 20
// captures of the default rig with different corner noise, the errors of the
// solved views against the truth match what the covariance predicts, with
// intrinsics from the views and with a ChArUco-like Gaussian prior. Corners
// here are the true projections plus Gaussian noise, so this checks the
// bundle adjustment's statistics; bench/calibration_uncertainty_bench.cpp
// does the same on rendered, detected captures. The same captures show that
// the views pass each camera's own intrinsics prior and reject the other's.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibration/calibration_report.h"
#include "calibration/capture_calibration.h"
#include "calibration/uncertainty_check.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/scene.h"
#include "tests/support/scene_calibration_input.h"

namespace hairrig {
namespace {

constexpr double kCornerNoisePx = 0.1;
constexpr int kCaptures = 20;

// The tags a view sees well: facing the camera by more than 25 degrees and
// 5 px inside the image, with noisy corners.
ViewObservations NoisyObservations(const Scene& scene, const ViewGroundTruth& truth,
                                   std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, kCornerNoisePx);
  ViewObservations out;
  const Eigen::Vector3d camera_in_box = truth.cam_from_box.Inverse().translation;
  for (const BoxTag& tag : scene.box.tags) {
    const Eigen::Vector3d normal = scene.box.faces[static_cast<size_t>(tag.face)].normal_box;
    const double facing = std::asin(
        std::clamp((camera_in_box - tag.center_box_mm).normalized().dot(normal), -1.0, 1.0));
    if (facing < DegToRad(25)) continue;
    TagObservation obs;
    obs.id = tag.id;
    bool inside = true;
    for (size_t k = 0; k < 4; ++k) {
      obs.corners_box_mm[k] = tag.corners_box_mm[k];
      const Eigen::Vector2d uv =
          Project(truth.intrinsics, truth.cam_from_box * tag.corners_box_mm[k]);
      inside = inside && uv.x() > 5 && uv.y() > 5 && uv.x() < truth.intrinsics.width_px - 6 &&
               uv.y() < truth.intrinsics.height_px - 6;
      obs.corners_px[k] = uv + Eigen::Vector2d(noise(rng), noise(rng));
    }
    if (inside) out.tags.push_back(obs);
  }
  return out;
}

CaptureCalibrationInput NoisyCapture(const Scene& scene, uint64_t seed) {
  std::mt19937_64 rng(seed);
  CaptureCalibrationInput input = hairrig_test::SceneCalibrationInput(scene);
  for (int v = 0; v < NumViews(scene); ++v) {
    const ViewGroundTruth truth = MakeViewGroundTruth(scene, v);
    CalibrationFrame frame;
    frame.name = "view " + std::to_string(v);
    frame.view = v;
    frame.camera = truth.camera_index;
    frame.stop = truth.stop;
    frame.turntable_deg = truth.turntable_deg;
    frame.observations = NoisyObservations(scene, truth, rng);
    input.frames.push_back(frame);
  }
  return input;
}

// A prior as a ChArUco calibration gives it: the truth plus an error drawn from its standard
// deviations.
void AddNoisyPriors(const Scene& scene, uint64_t seed, CaptureCalibrationInput* input) {
  std::mt19937_64 rng(seed * 7919 + 1);
  std::normal_distribution<double> unit(0.0, 1.0);
  const std::array<double, CameraIntrinsics::kNumParams> sd = {0.15,   0.15, 0.15,   0.18, 3e-4,
                                                               1.5e-3, 3e-5, 2.5e-5, 0};
  for (size_t c = 0; c < input->cameras.size(); ++c) {
    auto params = scene.cameras[c].intrinsics.ToParams();
    for (size_t p = 0; p < params.size(); ++p) params[p] += sd[p] * unit(rng);
    input->cameras[c].nominal = CameraIntrinsics::FromParams(
        params.data(), input->cameras[c].width_px, input->cameras[c].height_px);
    input->cameras[c].nominal_stddev = sd;
  }
}

UncertaintyRatios RatiosOverCaptures(const Scene& scene, bool with_prior, CalibrationMode mode) {
  std::vector<UncertaintySample> samples;
  double worst_prior_sigma =
      -INFINITY;  // the priors' check against the views (all the cameras' own)
  for (int seed = 1; seed <= kCaptures; ++seed) {
    CaptureCalibrationInput input = NoisyCapture(scene, static_cast<uint64_t>(seed));
    CaptureCalibrationOptions options;
    options.mode = mode;
    if (with_prior) {
      AddNoisyPriors(scene, static_cast<uint64_t>(seed), &input);
      options.fix_intrinsics = true;
    }
    auto result = CalibrateCapture(input, options);
    EXPECT_TRUE(result.ok()) << result.status().ToString();
    if (!result.ok()) continue;
    for (size_t c = 0; with_prior && c < result->cameras.size(); ++c) {
      const PriorCheck& check = result->cameras[c].prior_check;
      EXPECT_TRUE(check.tested) << check.not_tested;
      EXPECT_FALSE(check.rejected) << "seed " << seed << ": " << DescribePriorCheck(check);
      worst_prior_sigma = std::max(worst_prior_sigma, check.sigma);
    }
    for (size_t f = 0; f < input.frames.size(); ++f) {
      if (!result->frames[f].solved) continue;
      samples.push_back(
          MakeUncertaintySample(result->frames[f].cam_from_box,
                                MakeViewGroundTruth(scene, input.frames[f].view).cam_from_box,
                                result->frames[f].uncertainty));
    }
  }
  const UncertaintyRatios r = ObservedOverPredicted(samples);
  std::printf(
      "%s, %s mode, %d captures, %d views: observed / predicted rotation %.3f, centre %.3f "
      "(Mahalanobis %.3f, %.3f)\n",
      with_prior ? "Gaussian prior" : "intrinsics from the views",
      mode == CalibrationMode::kTurntable ? "turntable" : "free", kCaptures, r.views, r.rotation,
      r.centre, r.rotation_mahalanobis, r.centre_mahalanobis);
  if (with_prior)
    std::printf("  the priors' largest disagreement with the views: %.2f sigma\n",
                worst_prior_sigma);
  return r;
}

void ExpectTrustworthy(const UncertaintyRatios& r) {
  EXPECT_GT(r.views, kCaptures * 30);
  for (double ratio : {r.rotation, r.centre}) {
    EXPECT_GE(ratio, 0.8);
    EXPECT_LE(ratio, 1.25);
  }
}

class CalibrationUncertainty : public ::testing::Test {
 protected:
  void SetUp() override {
    auto scene = LoadScene("etc/scenes/default.yaml");
    ASSERT_TRUE(scene.ok()) << scene.status().ToString();
    scene_ = *scene;
  }
  Scene scene_;
};

TEST_F(CalibrationUncertainty, IntrinsicsFromTheViews) {
  ExpectTrustworthy(RatiosOverCaptures(scene_, false, CalibrationMode::kTurntable));
}

TEST_F(CalibrationUncertainty, GaussianChArUcoPrior) {
  ExpectTrustworthy(RatiosOverCaptures(scene_, true, CalibrationMode::kTurntable));
}

TEST_F(CalibrationUncertainty, FreeMode) {
  ExpectTrustworthy(RatiosOverCaptures(scene_, false, CalibrationMode::kFree));
}

// The upper camera's intrinsics file relabelled as the lower camera's: its
// views reject it, held softly or exactly, and the verdict fails naming the
// camera, the file and the parameter; each camera's own prior passes.
TEST_F(CalibrationUncertainty, TheViewsRejectAPriorOfTheOtherCamera) {
  CaptureCalibrationInput own = NoisyCapture(scene_, 1);
  AddNoisyPriors(scene_, 1, &own);
  for (CalibrationCamera& camera : own.cameras)
    camera.prior_source = camera.serial + "/intrinsics.json";
  CaptureCalibrationOptions options;
  options.fix_intrinsics = true;
  const auto good = CalibrateCapture(own, options);
  ASSERT_TRUE(good.ok()) << good.status().ToString();
  for (const CameraCalibration& camera : good->cameras) {
    std::printf("own prior: %s\n", DescribePriorCheck(camera.prior_check).c_str());
    EXPECT_TRUE(camera.prior_check.tested) << camera.prior_check.not_tested;
    EXPECT_FALSE(camera.prior_check.rejected) << DescribePriorCheck(camera.prior_check);
  }
  const CalibrationVerdict good_verdict = JudgeCalibration(own, *good);
  EXPECT_EQ(good_verdict.level, CalibrationVerdict::Level::kGood)
      << (good_verdict.reasons.empty() ? "" : good_verdict.reasons[0]);

  ASSERT_EQ(own.cameras.size(), 2u);
  ASSERT_EQ(own.cameras[1].serial, "SIM-CAM-LOWER");
  CaptureCalibrationInput relabelled = own;
  relabelled.cameras[1].nominal = own.cameras[0].nominal;
  relabelled.cameras[1].nominal_stddev = own.cameras[0].nominal_stddev;
  relabelled.cameras[1].prior_source = "upper_as_lower.json";
  for (const bool hard : {false, true}) {
    options.hard_prior = hard;
    const auto bad = CalibrateCapture(relabelled, options);
    ASSERT_TRUE(bad.ok()) << bad.status().ToString();
    const PriorCheck& check = bad->cameras[1].prior_check;
    std::printf("%s prior of the other camera: %s\n", hard ? "hard" : "soft",
                DescribePriorCheck(check).c_str());
    EXPECT_TRUE(check.rejected) << DescribePriorCheck(check);
    EXPECT_GT(check.sigma, 1.5 * options.prior_check.reject_sigma) << "not a clear rejection";
    EXPECT_FALSE(bad->cameras[0].prior_check.rejected)
        << DescribePriorCheck(bad->cameras[0].prior_check);
    const CalibrationVerdict verdict = JudgeCalibration(relabelled, *bad);
    EXPECT_EQ(verdict.level, CalibrationVerdict::Level::kFailed);
    ASSERT_FALSE(verdict.reasons.empty());
    const std::string& reason = verdict.reasons[0];
    for (const char* part : {"camera SIM-CAM-LOWER", "upper_as_lower.json", " sigma",
                             "check that upper_as_lower.json belongs to camera SIM-CAM-LOWER"})
      EXPECT_NE(reason.find(part), std::string::npos) << part << " not in: " << reason;
  }
}

// A prior for another image size is refused before anything is solved.
TEST_F(CalibrationUncertainty, APriorForAnotherImageSizeIsRefused) {
  CaptureCalibrationInput input = NoisyCapture(scene_, 2);
  AddNoisyPriors(scene_, 2, &input);
  input.cameras[0].nominal->width_px = 2 * input.cameras[0].width_px;
  input.cameras[0].prior_source = "half_size.json";
  CaptureCalibrationOptions options;
  options.fix_intrinsics = true;
  const auto result = CalibrateCapture(input, options);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(result.status().message().find("half_size.json"), std::string::npos)
      << result.status().message();
}

}  // namespace
}  // namespace hairrig
