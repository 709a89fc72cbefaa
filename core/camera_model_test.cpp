#include "core/camera_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <random>

namespace hairrig {
namespace {

CameraIntrinsics RandomCamera(std::mt19937& rng) {
  std::uniform_real_distribution<double> focal(500, 4000), dist(-0.3, 0.3), tang(-0.01, 0.01);
  CameraIntrinsics c;
  c.width_px = 2000;
  c.height_px = 1500;
  c.fx_px = focal(rng);
  c.fy_px = c.fx_px * std::uniform_real_distribution<double>(0.95, 1.05)(rng);
  c.cx_px = std::uniform_real_distribution<double>(900, 1100)(rng);
  c.cy_px = std::uniform_real_distribution<double>(650, 850)(rng);
  c.k1 = dist(rng);
  c.k2 = dist(rng) * 0.3;
  c.p1 = tang(rng);
  c.p2 = tang(rng);
  c.k3 = dist(rng) * 0.1;
  return c;
}

TEST(CameraModel, AgreesWithOpenCvProjectPoints) {
  std::mt19937 rng(7);
  double worst_relative = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const CameraIntrinsics c = RandomCamera(rng);
    std::uniform_real_distribution<double> xy(-400, 400), z(300, 3000);
    std::vector<cv::Point3d> points;
    for (int i = 0; i < 50; ++i) points.emplace_back(xy(rng), xy(rng), z(rng));
    const cv::Matx33d k(c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
    const std::vector<double> d = {c.k1, c.k2, c.p1, c.p2, c.k3};
    std::vector<cv::Point2d> expected;
    cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, d, expected);
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d uv = Project(c, Eigen::Vector3d(points[i].x, points[i].y, points[i].z));
      const double scale = std::max(std::hypot(expected[i].x, expected[i].y), 1.0);
      worst_relative = std::max(worst_relative,
                                std::hypot(uv.x() - expected[i].x, uv.y() - expected[i].y) / scale);
    }
  }
  std::printf("worst relative difference to cv::projectPoints: %.3g\n", worst_relative);
  EXPECT_LT(worst_relative, 1e-9);
}

TEST(CameraModel, UndistortInvertsProjection) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    CameraIntrinsics c = RandomCamera(rng);
    c.fx_px = c.fy_px =
        1500 + c.fx_px;  // lenses of the rig: the model is invertible over the image
    c.k1 *= 0.3;
    c.k2 *= 0.3;
    c.k3 *= 0.3;
    std::uniform_real_distribution<double> u(0, c.width_px), v(0, c.height_px);
    const Eigen::Vector2d pixel(u(rng), v(rng));
    auto normalized = UndistortPixel(c, pixel);
    ASSERT_TRUE(normalized.ok()) << normalized.status().ToString();
    const Eigen::Vector2d back = Project(c, Eigen::Vector3d(normalized->x(), normalized->y(), 1.0));
    EXPECT_NEAR((back - pixel).norm(), 0.0, 1e-6);
  }
}

// A 100 x 100 pixel pinhole camera with f = 100 px and no distortion.
CameraIntrinsics SmallCamera() {
  CameraIntrinsics c;
  c.width_px = c.height_px = 100;
  c.fx_px = c.fy_px = 100;
  c.cx_px = c.cy_px = 50;
  return c;
}

TEST(CameraModel, ProjectCheckedRefusesPointsBehind) {
  CameraIntrinsics c = SmallCamera();
  Eigen::Vector2d uv;
  EXPECT_FALSE(ProjectChecked(c, Eigen::Vector3d(0, 0, -1), &uv));
  EXPECT_TRUE(ProjectChecked(c, Eigen::Vector3d(0, 0, 1), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 50.0);
}

TEST(CameraModel, CheckNamesTheBadParameter) {
  CameraIntrinsics c = SmallCamera();
  EXPECT_TRUE(c.Check().ok());
  c.k2 = std::nan("");
  const Status s = c.Check();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("k2"), std::string::npos) << s.message();
  c.k2 = 0;
  c.fx_px = -1;
  EXPECT_FALSE(c.Check().ok());
  c.fx_px = 1e308;  // finite, but no lens
  const Status huge = c.Check();
  EXPECT_FALSE(huge.ok());
  EXPECT_NE(huge.message().find("1000 x the image's long side"), std::string::npos)
      << huge.message();
  c.fx_px = 999.0 * std::max(c.width_px, c.height_px);
  EXPECT_TRUE(c.Check().ok());
}

}  // namespace
}  // namespace hairrig
