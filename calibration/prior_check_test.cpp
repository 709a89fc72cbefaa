#include "calibration/prior_check.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace hairrig
