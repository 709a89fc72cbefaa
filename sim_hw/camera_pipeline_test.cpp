// The simulated camera's processing against what each step must do to a
// known input: flat fields, one bright point, a colour patch.
#include "sim_hw/camera_pipeline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "sim_hw/render_support.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

SceneCamera FlatCamera(const CameraPipeline& pipeline) {
  SceneCamera camera;
  camera.intrinsics.width_px = 256;
  camera.intrinsics.height_px = 256;
  camera.read_noise_dn = 1.5;
  camera.shot_noise_gain = 0.04;
  camera.pipeline = pipeline;
  return camera;
}

// Radiance that the nominal exposure records as `dn` (BGR).
cv::Mat3f FlatRadiance(const SceneCamera& camera, const cv::Vec3f& dn) {
  const float per_dn = 1.0f / static_cast<float>(255.0 * camera.exposure_s * camera.sensitivity);
  return cv::Mat3f(camera.intrinsics.height_px, camera.intrinsics.width_px, dn * per_dn);
}

cv::Mat Expose(const SceneCamera& camera, const cv::Vec3f& dn, bool noise) {
  return render_support::ExposeRadiance(FlatRadiance(camera, dn), camera, 0, 0, noise, 3);
}

TEST(CameraPipeline, TheIdentityRecordsTheRadianceAsItWas) {
  const SceneCamera camera = FlatCamera(CameraPipeline());
  ASSERT_TRUE(camera.pipeline.Identity());
  const cv::Mat image = Expose(camera, {40, 100, 200}, false);
  EXPECT_EQ(image.at<cv::Vec3b>(10, 10), cv::Vec3b(40, 100, 200));
}

// Noise measured on a flat field against the model: variance = read^2 + shot x DN,
// the shot noise's variance scaled by the ISO.
TEST(CameraPipeline, NoiseGrowsWithTheIsoAsStated) {
  for (double iso : {100.0, 800.0}) {
    CameraPipeline pipeline;
    pipeline.iso = iso;
    const SceneCamera camera = FlatCamera(pipeline);
    const cv::Mat image = Expose(camera, {100, 100, 100}, true);
    cv::Scalar mean, sd;
    cv::meanStdDev(image.reshape(1), mean, sd);
    const double read = camera.read_noise_dn;
    const double expected =
        std::sqrt(read * read + camera.shot_noise_gain * pipeline.ShotVarianceScale() * 100.0);
    EXPECT_NEAR(mean[0], 100.0, 0.3) << "iso " << iso;
    EXPECT_NEAR(sd[0], expected, 0.05 * expected) << "iso " << iso;
  }
}

TEST(CameraPipeline, ExposureErrorAndWhiteBalanceScaleTheChannels) {
  CameraPipeline pipeline;
  pipeline.exposure_ev = 1;
  pipeline.white_balance = {1.5, 1.0, 0.5};  // R, G, B
  const cv::Mat image = Expose(FlatCamera(pipeline), {40, 40, 40}, false);
  EXPECT_EQ(image.at<cv::Vec3b>(5, 5), cv::Vec3b(40, 80, 120));  // B x 2 x 0.5, G x 2, R x 2 x 1.5
}

TEST(CameraPipeline, TheSrgbCurveBrightensTheMidtones) {
  CameraPipeline pipeline;
  pipeline.tone = CameraPipeline::Tone::kSrgb;
  const cv::Mat image = Expose(FlatCamera(pipeline), {0.18f * 255, 255, 0}, false);
  const cv::Vec3b px = image.at<cv::Vec3b>(7, 7);
  EXPECT_NEAR(px[0], 118, 1);  // 18 % grey is 46 % of the range in sRGB
  EXPECT_EQ(px[1], 255);
  EXPECT_EQ(px[2], 0);
}

// A flat colour survives the mosaic and its demosaicing: each channel was
// sampled at a quarter or half of the photosites and filled in from them.
TEST(CameraPipeline, BayerDemosaicingKeepsAFlatColour) {
  CameraPipeline pipeline;
  pipeline.bayer = true;
  const cv::Mat image = Expose(FlatCamera(pipeline), {30, 90, 210}, false);
  for (int y : {40, 41}) {
    for (int x : {80, 81}) EXPECT_EQ(image.at<cv::Vec3b>(y, x), cv::Vec3b(30, 90, 210));
  }
}

TEST(CameraPipeline, JpegLosesDetailButKeepsTheImage) {
  CameraPipeline pipeline;
  pipeline.jpeg_quality = 60;
  const SceneCamera camera = FlatCamera(pipeline);
  cv::Mat3f radiance = FlatRadiance(camera, {60, 60, 60});
  const cv::Mat3f bright = FlatRadiance(camera, {200, 200, 200});
  for (int y = 0; y < radiance.rows; ++y)
    for (int x = 0; x < radiance.cols; ++x)
      if ((x / 3 + y / 5) % 2 == 0) radiance(y, x) = bright(y, x);
  const cv::Mat jpeg = render_support::ExposeRadiance(radiance, camera, 0, 0, false, 1);
  SceneCamera plain = camera;
  plain.pipeline = CameraPipeline();
  const cv::Mat exact = render_support::ExposeRadiance(radiance, plain, 0, 0, false, 1);
  const double psnr = cv::PSNR(jpeg, exact);
  EXPECT_GT(psnr, 22.0);
  EXPECT_LT(psnr, 60.0);  // it did change the image
}

TEST(CameraPipeline, CircleOfConfusionFollowsTheThinLens) {
  CameraPipeline pipeline;
  EXPECT_EQ(CircleOfConfusionPx(pipeline, 1750, 1000, 1200), 0.0);
  pipeline.f_number = 4;
  pipeline.pixel_um = 10;
  // f = 17.5 mm, aperture 4.375 mm, on the sensor in mm, then in 10 um pixels:
  const double f = 17.5, expected_mm = (f / 4) * (f / (1000 - f)) * (200.0 / 1200.0);
  EXPECT_NEAR(CircleOfConfusionPx(pipeline, 1750, 1000, 1200), expected_mm / 0.010, 1e-9);
  EXPECT_NEAR(CircleOfConfusionPx(pipeline, 1750, 1000, 1000), 0.0, 1e-12);
  // The backdrop at infinity: the largest blur behind the focus.
  EXPECT_GT(CircleOfConfusionPx(pipeline, 1750, 1000, INFINITY),
            CircleOfConfusionPx(pipeline, 1750, 1000, 5000));
}

// A bright point out of focus spreads over a Gaussian of sigma = half its circle of confusion.
TEST(CameraPipeline, DefocusSpreadsAPointByItsCircleOfConfusion) {
  CameraPipeline pipeline;
  pipeline.f_number = 2;
  pipeline.pixel_um = 20;
  cv::Mat3f radiance(101, 101, cv::Vec3f(0, 0, 0));
  radiance(50, 50) = cv::Vec3f(1, 1, 1);
  const double focal = 1750, focus = 1000, z = 1200;
  const cv::Mat1f depth(101, 101, static_cast<float>(z));
  const double sigma = 0.5 * CircleOfConfusionPx(pipeline, focal, focus, z);
  ASSERT_GT(sigma, 2.0);
  ASSERT_LT(sigma, 12.0);
  const cv::Mat3f blurred = DefocusRadiance(radiance, depth, pipeline, focal, focus);
  double sum = 0, second = 0;
  for (int y = 0; y < 101; ++y) {
    for (int x = 0; x < 101; ++x) {
      const double w = blurred(y, x)[1];
      sum += w;
      second += w * (x - 50) * (x - 50);
    }
  }
  EXPECT_NEAR(sum, 1.0, 1e-3);
  EXPECT_NEAR(std::sqrt(second / sum), sigma, 0.1 * sigma);
  // In focus, nothing moves.
  const cv::Mat1f in_focus(101, 101, static_cast<float>(focus));
  EXPECT_EQ(DefocusRadiance(radiance, in_focus, pipeline, focal, focus)(50, 50)[1], 1.0f);
}

// A path tracer's grain: a log-normal factor per pixel of mean 1 (the field
// stays as bright), the same on every channel, none in a render without noise.
TEST(CameraPipeline, RenderGrainIsALogNormalFactorPerPixel) {
  CameraPipeline pipeline;
  pipeline.render_grain_sd = 0.5;
  SceneCamera camera = FlatCamera(pipeline);
  camera.read_noise_dn = 0;
  camera.shot_noise_gain = 0;
  const cv::Mat image = Expose(camera, {60, 60, 60}, true);
  cv::Scalar mean, sd;
  cv::meanStdDev(image.reshape(1), mean, sd);
  const double expected_sd = 60.0 * std::sqrt(std::exp(0.25) - 1.0);  // 32 DN
  EXPECT_NEAR(mean[0], 60.0, 1.0);
  EXPECT_NEAR(sd[0], expected_sd, 0.05 * expected_sd);
  int channels_apart = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b v = image.at<cv::Vec3b>(y, x);
      channels_apart += v[0] != v[1] || v[1] != v[2];
    }
  }
  EXPECT_EQ(channels_apart, 0);
  EXPECT_EQ(Expose(camera, {60, 60, 60}, false).at<cv::Vec3b>(5, 5), cv::Vec3b(60, 60, 60));
}

TEST(CameraPipeline, CheckNamesTheField) {
  CameraPipeline pipeline;
  EXPECT_TRUE(pipeline.Check().ok());
  pipeline.jpeg_quality = 101;
  EXPECT_TRUE(IsInvalidNaming(pipeline.Check(), "camera_pipeline.jpeg_quality"));
  pipeline = CameraPipeline();
  pipeline.iso = NAN;
  EXPECT_TRUE(IsInvalidNaming(pipeline.Check(), "camera_pipeline.iso"));
  pipeline = CameraPipeline();
  pipeline.white_balance.x() = 0;
  EXPECT_TRUE(IsInvalidNaming(pipeline.Check(), "camera_pipeline.white_balance"));
  pipeline = CameraPipeline();
  pipeline.render_grain_sd = -0.1;
  EXPECT_TRUE(IsInvalidNaming(pipeline.Check(), "camera_pipeline.render_grain_sd"));
}

}  // namespace
}  // namespace hairrig
