// Box matching and per-view pose on synthetic views: the box model of
// etc/calib-box.yaml projected through a distorted camera with corner noise.
#include "calibration/view_pose.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace hairrig {
namespace {

CameraIntrinsics Camera() {
  CameraIntrinsics c;
  c.width_px = 1200;
  c.height_px = 1600;
  c.fx_px = c.fy_px = 2400;
  c.cx_px = 601.5;
  c.cy_px = 797.0;
  c.k1 = -0.06;
  c.k2 = 0.02;
  c.p1 = 3e-4;
  return c;
}

// The box turned so that three faces face the camera, 900 mm away.
Rigid3d TrueCamFromBox() {
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(-0.6, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(2.2, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  return Rigid3d(r, Eigen::Vector3d(12, -25, 900));
}

// Every tag on a face turned towards the camera, corners with Gaussian noise.
std::vector<TagDetection> SyntheticDetections(const CalibBox& box, double noise_px, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  const Rigid3d cam_from_box = TrueCamFromBox();
  const CameraIntrinsics camera = Camera();
  std::vector<TagDetection> out;
  for (const BoxTag& tag : box.tags) {
    const BoxFace& face = box.faces[static_cast<size_t>(tag.face)];
    const Eigen::Vector3d normal_cam = cam_from_box.rotation * face.normal_box;
    if (normal_cam.dot(cam_from_box * tag.center_box_mm) >
        -0.3 * (cam_from_box * tag.center_box_mm).norm())
      continue;
    TagDetection d;
    d.id = tag.id;
    for (int k = 0; k < 4; ++k) {
      d.corners_px[static_cast<size_t>(k)] =
          Project(camera, cam_from_box * tag.corners_box_mm[static_cast<size_t>(k)]) +
          Eigen::Vector2d(noise(rng), noise(rng));
    }
    out.push_back(d);
  }
  return out;
}

double RotationErrorDeg(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation) * 180 / 3.14159265358979;
}

class ViewPoseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto box = LoadCalibBox("etc/calib-box.yaml");
    ASSERT_TRUE(box.ok()) << box.status().ToString();
    box_ = *box;
  }
  CalibBox box_;
};

TEST_F(ViewPoseTest, RecoversThePoseFromNoisyCorners) {
  const auto detections = SyntheticDetections(box_, 0.2, 1);
  ASSERT_GE(detections.size(), 8u);
  const ViewObservations obs = MatchToBox(detections, box_);
  EXPECT_TRUE(obs.rejected.empty());
  auto pose = EstimateViewPose(obs, Camera());
  ASSERT_TRUE(pose.ok()) << pose.status().ToString();
  EXPECT_EQ(pose->tags_used, static_cast<int>(detections.size()));
  EXPECT_LT(RotationErrorDeg(pose->cam_from_box, TrueCamFromBox()), 0.05);
  EXPECT_LT((pose->cam_from_box.translation - TrueCamFromBox().translation).norm(), 1.0);
  EXPECT_NEAR(pose->rms_px, 0.2 * std::sqrt(2.0),
              0.06);  // the 2D corner noise (sigma 0.2 px per axis)
}

TEST_F(ViewPoseTest, UnknownDuplicateAndInconsistentTagsAreReportedAndLeftOut) {
  auto detections = SyntheticDetections(box_, 0.2, 2);
  ASSERT_GE(detections.size(), 8u);
  TagDetection stranger = detections[0];
  stranger.id = 999;
  detections.push_back(stranger);
  detections.push_back(detections[1]);  // the same id twice
  const int moved_id = detections[2].id;
  for (auto& c : detections[2].corners_px) c += Eigen::Vector2d(14, -9);  // a tag stuck on crooked
  const ViewObservations obs = MatchToBox(detections, box_);
  ASSERT_EQ(obs.rejected.size(), 3u);  // 999 and both copies of the duplicate
  EXPECT_EQ(obs.rejected[0].id, detections[1].id);
  auto pose = EstimateViewPose(obs, Camera());
  ASSERT_TRUE(pose.ok()) << pose.status().ToString();
  bool moved_reported = false, stranger_reported = false;
  for (const RejectedTag& r : pose->rejected) {
    moved_reported |= r.id == moved_id && r.reason.find("disagree") != std::string::npos;
    stranger_reported |=
        r.id == 999 && r.reason.find("not on the calibration box") != std::string::npos;
  }
  EXPECT_TRUE(moved_reported);
  EXPECT_TRUE(stranger_reported);
  EXPECT_LT(RotationErrorDeg(pose->cam_from_box, TrueCamFromBox()), 0.05);
  EXPECT_LT(pose->rms_px, 0.35);
}

TEST_F(ViewPoseTest, TooFewTagsOrBadInputGiveClearErrors) {
  auto detections = SyntheticDetections(box_, 0.2, 3);
  detections.resize(1);
  auto pose = EstimateViewPose(MatchToBox(detections, box_), Camera());
  ASSERT_FALSE(pose.ok());
  EXPECT_NE(pose.status().message().find("1 usable tag(s), 2 needed"), std::string::npos)
      << pose.status().message();

  pose = EstimateViewPose(MatchToBox({}, box_), Camera());
  ASSERT_FALSE(pose.ok());
  EXPECT_NE(pose.status().message().find("no tag of the box"), std::string::npos)
      << pose.status().message();

  detections = SyntheticDetections(box_, 0.2, 3);
  detections[0].corners_px[1].x() = std::nan("");
  const ViewObservations obs = MatchToBox(detections, box_);
  ASSERT_EQ(obs.rejected.size(), 1u);
  EXPECT_NE(obs.rejected[0].reason.find("not finite"), std::string::npos);

  CameraIntrinsics broken = Camera();
  broken.fx_px = -1;
  EXPECT_EQ(EstimateViewPose(obs, broken).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
