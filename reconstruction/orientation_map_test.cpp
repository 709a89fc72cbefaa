#include "reconstruction/orientation_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

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
