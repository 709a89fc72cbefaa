#include "calibration/prior_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "calibration/apriltag_detector.h"
#include "calibration/capture_calibration.h"
#include "calibration/charuco_intrinsics.h"
#include "calibration/intrinsics_folder.h"
#include "calibration/view_pose.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

CameraIntrinsics Camera(double fx) {
  CameraIntrinsics c;
  c.width_px = 1200, c.height_px = 1600;
  c.fx_px = fx, c.fy_px = fx, c.cx_px = 600, c.cy_px = 800, c.k1 = -0.03;
  return c;
}

// The views' covariance: 1 px on fx, fy, cx, cy, 1e-3 on k1..p2, with fx and
// fy correlated 0.9; k3 held (row and column 0).
IntrinsicsCovariance ViewsCovariance() {
  IntrinsicsCovariance c = IntrinsicsCovariance::Zero();
  for (int i = 0; i < 4; ++i) c(i, i) = 1;
  for (int i = 4; i < 8; ++i) c(i, i) = 1e-6;
  c(0, 1) = c(1, 0) = 0.9;
  return c;
}

// Values of the exact chi-square tail, as normal deviates (computed apart).
TEST(PriorCheck, ChiSquareSigmaIsTheWilsonHilfertyDeviate) {
  EXPECT_NEAR(ChiSquareSigma(45.57, 8), 4.88, 0.01);  // exact: 5.0
  EXPECT_NEAR(ChiSquareSigma(8, 8), 0.17, 0.01);      // the mean: about the median
  EXPECT_LT(ChiSquareSigma(0, 8), -5);
  EXPECT_EQ(ChiSquareSigma(10, 0), 0);
}

TEST(PriorCheck, TheSamePriorPassesAndAnotherIsRejectedNamingFx) {
  const std::array<double, CameraIntrinsics::kNumParams> prior_sd = {0.2,  0.2,  0.2,  0.2, 1e-4,
                                                                     1e-4, 1e-5, 1e-5, 0};
  const PriorCheck same =
      CheckIntrinsicsPrior(Camera(1750), prior_sd, Camera(1750.5), ViewsCovariance());
  ASSERT_TRUE(same.tested) << same.not_tested;
  EXPECT_EQ(same.dof, 8);
  EXPECT_FALSE(same.rejected) << DescribePriorCheck(same);

  const PriorCheck other =
      CheckIntrinsicsPrior(Camera(1750), prior_sd, Camera(1760), ViewsCovariance());
  ASSERT_TRUE(other.tested);
  EXPECT_TRUE(other.rejected) << DescribePriorCheck(other);
  EXPECT_EQ(other.worst_param, 0);
  EXPECT_NEAR(other.worst_param_sigma, 10 / std::sqrt(1 + 0.04), 1e-9);
  EXPECT_NE(DescribePriorCheck(other).find("fx_px 1750.0 (prior) vs 1760.0 (views) px"),
            std::string::npos)
      << DescribePriorCheck(other);
}

TEST(PriorCheck, AnUnknownCovarianceIsNotTested) {
  const PriorCheck check =
      CheckIntrinsicsPrior(Camera(1750), {}, Camera(1760), IntrinsicsCovariance::Constant(NAN));
  EXPECT_FALSE(check.tested);
  EXPECT_FALSE(check.rejected);
  EXPECT_NE(DescribePriorCheck(check).find("not tested"), std::string::npos);
}

// The calibration options refuse a bad value with InvalidArgument naming the
// field; a nested struct's field is named after the field holding it.
TEST(CalibrationOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(TagDetectorOptions{}.Check().ok());
  EXPECT_TRUE(ViewPoseOptions{}.Check().ok());
  EXPECT_TRUE(PriorCheckOptions{}.Check().ok());
  EXPECT_TRUE(BundleAdjustmentOptions{}.Check().ok());
  EXPECT_TRUE(ChArUcoCalibrationOptions{}.Check().ok());
  EXPECT_TRUE(CaptureCalibrationOptions{}.Check().ok());
  {
    TagDetectorOptions o;
    o.max_hamming = 4;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "max_hamming"));
    o = TagDetectorOptions{};
    o.decimate = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "decimate"));
    o = TagDetectorOptions{};
    o.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
  }
  {
    ViewPoseOptions o;
    o.ransac_threshold_px = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "ransac_threshold_px"));
    o = ViewPoseOptions{};
    o.max_tag_rms_px = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "max_tag_rms_px"));
    o = ViewPoseOptions{};
    o.min_tags = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "min_tags"));
  }
  {
    PriorCheckOptions o;
    o.reject_sigma = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "reject_sigma"));
  }
  {
    BundleAdjustmentOptions o;
    o.huber_px = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "huber_px"));
    o = BundleAdjustmentOptions{};
    o.max_iterations = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "max_iterations"));
    o = BundleAdjustmentOptions{};
    o.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
  }
  {
    ChArUcoCalibrationOptions o;
    o.min_corners = 3;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "min_corners"));
    o = ChArUcoCalibrationOptions{};
    o.min_images = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "min_images"));
  }
  {
    CaptureCalibrationOptions o;
    o.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "threads"));
    o = CaptureCalibrationOptions{};
    o.huber_px = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "huber_px"));
    o = CaptureCalibrationOptions{};
    o.detector.max_hamming = 9;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "detector: max_hamming"));
    o = CaptureCalibrationOptions{};
    o.pose.min_tags = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "pose: min_tags"));
    o = CaptureCalibrationOptions{};
    o.prior_check.reject_sigma = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "prior_check: reject_sigma"));
  }
  {
    IntrinsicsFolderOptions o;
    o.images_dir = "images";
    o.board_file = "board.yaml";
    o.serial = "CAM-1";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.calibration.min_images = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "calibration: min_images"));
  }
}

// The entry points taking the options refuse bad ones before any work.
TEST(CalibrationOptions, EntryPointsCheckTheirOptions) {
  TagDetectorOptions detector;
  detector.max_hamming = -1;
  const auto created = TagDetector::Create(detector);
  ASSERT_FALSE(created.ok());
  EXPECT_NE(created.status().message().find("max_hamming"), std::string::npos);

  ViewPoseOptions pose;
  pose.min_tags = 0;
  const Result<ViewPose> view = EstimateViewPose(ViewObservations{}, Camera(1750), pose);
  ASSERT_FALSE(view.ok());
  EXPECT_NE(view.status().message().find("min_tags"), std::string::npos);

  BundleAdjustmentOptions ba;
  ba.huber_px = 0;
  const Result<BundleAdjustmentResult> solved = RunBundleAdjustment(BundleAdjustmentInput{}, ba);
  ASSERT_FALSE(solved.ok());
  EXPECT_NE(solved.status().message().find("huber_px"), std::string::npos);

  ChArUcoCalibrationOptions charuco;
  charuco.threads = 0;
  const Result<ChArUcoCalibration> intrinsics =
      CalibrateIntrinsicsFromChArUco({"a.png"}, ChArUcoBoard{}, charuco);
  ASSERT_FALSE(intrinsics.ok());
  EXPECT_NE(intrinsics.status().message().find("threads"), std::string::npos);

  CaptureCalibrationOptions capture;
  capture.pose.ransac_threshold_px = 0;
  const Result<CaptureCalibration> calibrated =
      CalibrateCapture(CaptureCalibrationInput{}, capture);
  ASSERT_FALSE(calibrated.ok());
  EXPECT_NE(calibrated.status().message().find("pose: ransac_threshold_px"), std::string::npos);

  PriorCheckOptions prior;
  prior.reject_sigma = 0;
  const PriorCheck check =
      CheckIntrinsicsPrior(Camera(1750), {}, Camera(1760), ViewsCovariance(), prior);
  EXPECT_FALSE(check.tested);
  EXPECT_NE(check.not_tested.find("reject_sigma"), std::string::npos) << check.not_tested;
}

}  // namespace
}  // namespace hairrig
