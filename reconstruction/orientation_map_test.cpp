#include "reconstruction/orientation_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "core/status.h"
#include "core/transform.h"

namespace hairrig {
namespace {

// Thin bright lines along `angle_deg` at irregular spacing on a dark ground,
// drawn anti-aliased, with a little noise: a patch of straight hair.
cv::Mat Lines(double angle_deg, uint32_t seed, int size = 96) {
  cv::Mat image(size, size, CV_8U, cv::Scalar(40));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> gap(2.5, 5.5);
  const double a = DegToRad(angle_deg);
  const cv::Point2d along(std::cos(a), std::sin(a)), across(-std::sin(a), std::cos(a));
  const cv::Point2d centre(size / 2.0, size / 2.0);
  constexpr int kShift = 4;  // sub-pixel line ends
  for (double offset = -size; offset < size; offset += gap(rng)) {
    const cv::Point2d p0 = centre + across * offset - along * (2.0 * size),
                      p1 = centre + across * offset + along * (2.0 * size);
    cv::line(image, cv::Point(cvRound(p0.x * 16), cvRound(p0.y * 16)),
             cv::Point(cvRound(p1.x * 16), cvRound(p1.y * 16)), cv::Scalar(200), 1, cv::LINE_AA,
             kShift);
  }
  cv::Mat noise(image.size(), CV_8S);
  cv::randn(noise, 0, 6);
  cv::Mat out;
  cv::add(image, noise, out, cv::noArray(), CV_8U);
  return out;
}

TEST(OrientationMap, FindsTheDirectionOfThinLinesWithinADegree) {
  std::vector<double> errors;
  for (int i = 0; i < 12; ++i) {
    const double truth = 7.5 + 15.0 * i;  // off the bank's directions on purpose
    auto map = ComputeOrientationMap(Lines(truth, static_cast<uint32_t>(i)), cv::Mat(),
                                     OrientationOptions{});
    ASSERT_TRUE(map.ok()) << map.status().ToString();
    for (int y = 24; y < 72; y += 3) {
      for (int x = 24; x < 72; x += 3)
        errors.push_back(OrientationDifferenceDeg(map->angle_deg(y, x), truth));
    }
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 1.0);
  EXPECT_LT(errors[errors.size() * 9 / 10], 3.0);
}

// Wisps whose flow shows only at their own scale: broad soft bands along
// `angle_deg` (16 px apart) under pixel-scale grain stronger than their contrast.
cv::Mat Wisps(double angle_deg, uint32_t seed, int size = 192) {
  cv::Mat1f bands(size, size);
  const double a = DegToRad(angle_deg);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double across = -x * std::sin(a) + y * std::cos(a);
      bands(y, x) = static_cast<float>(110 + 40 * std::cos(2 * kPi * across / 16.0));
    }
  }
  cv::Mat1f grain(bands.size());
  cv::theRNG().state = seed;
  cv::randn(grain, 0, 45);
  cv::Mat out;
  cv::Mat1f(bands + grain).convertTo(out, CV_8U);
  return out;
}

// Median angle error over the centre of a map.
double CentreMedianErrorDeg(const OrientationMap& map, double truth_deg) {
  std::vector<double> errors;
  const int margin = map.angle_deg.rows / 4;
  for (int y = margin; y < map.angle_deg.rows - margin; y += 3) {
    for (int x = margin; x < map.angle_deg.cols - margin; x += 3)
      errors.push_back(OrientationDifferenceDeg(map.angle_deg(y, x), truth_deg));
  }
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

// The pyramid finds the flow the fine bank alone cannot see, and keeps the
// fine bank's answer where fibres are sharp.
// Luo et al.'s filter: the image alone, unsmoothed.
OrientationOptions LuoFilter() {
  OrientationOptions o;
  o.scales = 1;
  o.smoothing_px = 0;
  return o;
}

TEST(OrientationMap, ScalesFindFlowAtTheScaleOfWisps) {
  const OrientationOptions fine = LuoFilter();
  OrientationOptions pyramid = LuoFilter();
  pyramid.scales = 3;
  double fine_error = 0, pyramid_error = 0, lines_error = 0;
  for (int i = 0; i < 4; ++i) {
    const double truth = 12.5 + 45.0 * i;
    const cv::Mat wisps = Wisps(truth, static_cast<uint32_t>(i + 1));
    auto at_fine = ComputeOrientationMap(wisps, cv::Mat(), fine);
    auto at_all = ComputeOrientationMap(wisps, cv::Mat(), pyramid);
    auto lines = ComputeOrientationMap(Lines(truth, static_cast<uint32_t>(i)), cv::Mat(), pyramid);
    ASSERT_TRUE(at_fine.ok() && at_all.ok() && lines.ok());
    fine_error += CentreMedianErrorDeg(*at_fine, truth) / 4;
    pyramid_error += CentreMedianErrorDeg(*at_all, truth) / 4;
    lines_error += CentreMedianErrorDeg(*lines, truth) / 4;
  }
  std::printf("median error on wisps: one scale %.1f deg, three %.1f deg; on thin lines %.2f deg\n",
              fine_error, pyramid_error, lines_error);
  EXPECT_GT(fine_error, 10.0);
  EXPECT_LT(pyramid_error, 5.0);
  EXPECT_LT(lines_error, 1.0);
}

// Smoothing keeps a straight flow that glints along the fibres scatter pixel
// by pixel, and leaves clean lines as they were.
TEST(OrientationMap, SmoothingRecoversFlowUnderFibreGlints) {
  const OrientationOptions plain = LuoFilter();
  OrientationOptions smoothed = LuoFilter();
  smoothed.smoothing_px = 3;
  double plain_error = 0, smoothed_error = 0, clean_error = 0;
  for (int i = 0; i < 4; ++i) {
    const double truth = 20.0 + 40.0 * i;
    const cv::Mat clean = Lines(truth, static_cast<uint32_t>(i + 7), 128);
    cv::Mat1f glints(clean.size());
    cv::theRNG().state = static_cast<uint64_t>(i + 11);
    cv::randn(glints, 0, 0.8);
    cv::exp(glints, glints);
    cv::Mat1f lines;
    clean.convertTo(lines, CV_32F, 1.0, -40.0);  // the lines above the ground
    cv::Mat grainy;
    cv::Mat1f(lines.mul(glints)).convertTo(grainy, CV_8U, 1.0, 40.0);
    auto a = ComputeOrientationMap(grainy, cv::Mat(), plain);
    auto b = ComputeOrientationMap(grainy, cv::Mat(), smoothed);
    auto c = ComputeOrientationMap(clean, cv::Mat(), smoothed);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok());
    plain_error += CentreMedianErrorDeg(*a, truth) / 4;
    smoothed_error += CentreMedianErrorDeg(*b, truth) / 4;
    clean_error += CentreMedianErrorDeg(*c, truth) / 4;
  }
  std::printf(
      "median error under glints: plain %.2f deg, smoothed %.2f deg; clean lines %.2f deg\n",
      plain_error, smoothed_error, clean_error);
  EXPECT_LT(smoothed_error, 0.7 * plain_error);
  EXPECT_LT(clean_error, 1.0);
}

// The default (three scales, smoothing 2 px) on both kinds of image: wisps
// under pixel-scale grain and sharp lines.
TEST(OrientationMap, TheDefaultHoldsOnWispsAndOnLines) {
  const OrientationOptions options;
  double wisps_error = 0, lines_error = 0;
  for (int i = 0; i < 4; ++i) {
    const double truth = 12.5 + 45.0 * i;
    auto wisps =
        ComputeOrientationMap(Wisps(truth, static_cast<uint32_t>(i + 1)), cv::Mat(), options);
    auto lines = ComputeOrientationMap(Lines(truth, static_cast<uint32_t>(i)), cv::Mat(), options);
    ASSERT_TRUE(wisps.ok() && lines.ok());
    wisps_error += CentreMedianErrorDeg(*wisps, truth) / 4;
    lines_error += CentreMedianErrorDeg(*lines, truth) / 4;
  }
  std::printf("the default's median error: wisps %.2f deg, thin lines %.2f deg\n", wisps_error,
              lines_error);
  EXPECT_LT(wisps_error, 5.0);
  EXPECT_LT(lines_error, 1.0);
}

TEST(OrientationMap, LinesAreConfidentAndNoiseIsNot) {
  cv::Mat noise(96, 96, CV_8U);
  cv::randu(noise, 0, 255);
  auto lines = ComputeOrientationMap(Lines(30, 1), cv::Mat(), OrientationOptions{});
  auto random = ComputeOrientationMap(noise, cv::Mat(), OrientationOptions{});
  ASSERT_TRUE(lines.ok() && random.ok());
  const cv::Rect inner(24, 24, 48, 48);
  const double line_confidence = cv::mean(lines->confidence(inner))[0];
  const double noise_confidence = cv::mean(random->confidence(inner))[0];
  // Measured: 0.95 on the lines, 0.55 on uniform noise.
  EXPECT_GT(line_confidence, 0.85);
  EXPECT_LT(noise_confidence, 0.65);
}

// The responses sit where the fibres are: the even kernel's response to a
// single bright vertical line peaks on the line, also next to the image's
// border (where the filter sees the image's mirror image), and an image
// smaller than the kernels is filtered too.
TEST(OrientationMap, ResponsesPeakOnTheLineUpToTheBorder) {
  OrientationOptions one_scale;
  one_scale.scales = 1;
  one_scale.smoothing_px = 0;
  one_scale.quadrature = false;
  for (const int line_x : {40, 3}) {
    cv::Mat1b image(64, 80, uint8_t{40});
    image.col(line_x).setTo(220);
    auto map = ComputeOrientationMap(image, cv::Mat(), one_scale);
    ASSERT_TRUE(map.ok());
    cv::Point peak;
    cv::minMaxLoc(map->response.row(32), nullptr, nullptr, nullptr, &peak);
    EXPECT_LE(std::abs(peak.x - line_x), 1) << "line at x = " << line_x;
    EXPECT_LT(OrientationDifferenceDeg(map->angle_deg(32, line_x), 90), 2.0);
  }
  cv::Mat1b tiny(6, 9, uint8_t{40});
  tiny.col(4).setTo(220);
  auto map = ComputeOrientationMap(tiny, cv::Mat(), OrientationOptions{});
  ASSERT_TRUE(map.ok());
  EXPECT_EQ(map->angle_deg.size(), tiny.size());
  EXPECT_TRUE(std::isfinite(map->angle_deg(3, 4)));
}

TEST(OrientationMap, OutsideTheRegionIsUnknown) {
  cv::Mat1b region(96, 96, uint8_t{0});
  region(cv::Rect(30, 30, 20, 20)).setTo(255);
  auto map = ComputeOrientationMap(Lines(60, 2), region, OrientationOptions{});
  ASSERT_TRUE(map.ok());
  EXPECT_TRUE(std::isnan(map->angle_deg(5, 5)));
  EXPECT_EQ(map->confidence(5, 5), 0.0f);
  EXPECT_LT(OrientationDifferenceDeg(map->angle_deg(40, 40), 60), 3.0);
}

TEST(OrientationMap, BadInputIsRefused) {
  OrientationOptions bad;
  bad.directions = 2;
  EXPECT_FALSE(ComputeOrientationMap(Lines(0, 1), cv::Mat(), bad).ok());
  for (const auto& [scales, smoothing] : {std::pair{0, 0.0}, {6, 0.0}, {1, -1.0}, {1, NAN}}) {
    OrientationOptions o;
    o.scales = scales;
    o.smoothing_px = smoothing;
    EXPECT_EQ(o.Check().code(), StatusCode::kInvalidArgument) << scales << " " << smoothing;
  }
  EXPECT_FALSE(ComputeOrientationMap(cv::Mat(), cv::Mat(), OrientationOptions{}).ok());
  EXPECT_FALSE(ComputeOrientationMap(Lines(0, 1), cv::Mat1b(10, 10), OrientationOptions{}).ok());
  cv::Mat1f floats(10, 10);
  EXPECT_FALSE(ComputeOrientationMap(floats, cv::Mat(), OrientationOptions{}).ok());
}

TEST(OrientationMap, DifferenceIsUnsigned) {
  EXPECT_DOUBLE_EQ(OrientationDifferenceDeg(5, 175), 10);
  EXPECT_DOUBLE_EQ(OrientationDifferenceDeg(0, 90), 90);
  EXPECT_DOUBLE_EQ(OrientationDifferenceDeg(10, 370), 0);
}

}  // namespace
}  // namespace hairrig
