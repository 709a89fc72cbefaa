#include "reconstruction/reconstruction_verdict.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "reconstruction/hair_segmentation.h"
#include "reconstruction/skin_views.h"
#include "tests/support/verdict_reasons.h"

namespace hairrig {
namespace {

using hairrig_test::HasReasonWith;

// Ten views with clear orientation, 60 % of the depth cells confirmed.
PointReconstructionSummary SoundPoints() {
  PointReconstructionSummary s;
  for (int i = 0; i < 10; ++i) {
    ViewPointsSummary v;
    v.name = "00" + std::to_string(i) + "_CAM";
    v.median_orientation_confidence = 0.4;
    s.views.push_back(v);
  }
  s.fusion.candidates = 1000;
  s.fusion.consistent = 600;
  s.fusion.depth_confirmed = 800;
  s.fusion.points = 500;
  s.fusion.depth_pairs = 2000;
  s.fusion.direction_pairs = 1400;  // 70 %
  return s;
}

StrandPlausibility SoundStrands() {
  StrandPlausibility s;
  s.strands = 100;
  s.median_length_mm = 180;
  s.hair_extent_mm = 300;
  s.views_measured = 10;
  s.samples_facing = 1000;
  s.samples_over_skin = 5;
  return s;
}

TEST(ReconstructionVerdict, ASoundReconstructionIsGood) {
  const PointReconstructionSummary points = SoundPoints();
  const StrandPlausibility strands = SoundStrands();
  const ReconstructionVerdict v = JudgeReconstruction(&points, &strands);
  EXPECT_STREQ(v.name(), "good");
  EXPECT_TRUE(v.reasons.empty());
  EXPECT_STREQ(JudgeReconstruction(nullptr, nullptr).name(), "good");
}

TEST(ReconstructionVerdict, ViewsThatAgreeOnDepthButNotOnDirectionFailWithTheReason) {
  PointReconstructionSummary points = SoundPoints();
  points.fusion.direction_pairs = 400;  // 20 %
  ReconstructionVerdict v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "failed");
  EXPECT_TRUE(HasReasonWith(v, "only 20.0 % agree on its direction"))
      << ::testing::PrintToString(v.reasons);
  points.fusion.direction_pairs = 700;  // 35 %: between failed and check
  v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "check");
  EXPECT_TRUE(HasReasonWith(v, "35.0 %"));
  points.fusion.depth_pairs = 0;  // not counted: not judged
  EXPECT_STREQ(JudgeReconstruction(&points, nullptr).name(), "good");
}

TEST(ReconstructionVerdict, ViewsThatHardlyAgreeOrFindNothingFail) {
  PointReconstructionSummary points = SoundPoints();
  points.fusion.depth_confirmed = 30;  // 3 %
  ReconstructionVerdict v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "failed");
  EXPECT_TRUE(HasReasonWith(v, "only 3.0 % of the depth cells are at a depth another view"))
      << ::testing::PrintToString(v.reasons);
  points = SoundPoints();
  points.fusion.points = 0;
  v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "failed");
  EXPECT_TRUE(HasReasonWith(v, "no points")) << ::testing::PrintToString(v.reasons);
  points.fusion.candidates = 0;
  EXPECT_TRUE(HasReasonWith(JudgeReconstruction(&points, nullptr), "found no depth"));
}

TEST(ReconstructionVerdict, ViewsWithoutClearOrientationAreNamed) {
  PointReconstructionSummary points = SoundPoints();
  points.views[3].median_orientation_confidence = 0.02;
  ReconstructionVerdict v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "check");
  ASSERT_EQ(v.views_to_check.size(), 1u);
  EXPECT_EQ(v.views_to_check[0], "003_CAM");
  EXPECT_TRUE(HasReasonWith(v, "view 003_CAM: the hair's orientation is unclear"));
  for (int i = 0; i < 6; ++i) points.views[i].median_orientation_confidence = 0.02;
  v = JudgeReconstruction(&points, nullptr);
  EXPECT_STREQ(v.name(), "failed");
  EXPECT_TRUE(HasReasonWith(v, "6 of 10 views show no clear hair orientation"));
}

TEST(ReconstructionVerdict, ShortStrandsAndStrandsOverSkinAreReported) {
  StrandPlausibility strands = SoundStrands();
  strands.median_length_mm = 30;  // 10 % of the hair's extent
  ReconstructionVerdict v = JudgeReconstruction(nullptr, &strands);
  EXPECT_STREQ(v.name(), "check");
  EXPECT_TRUE(HasReasonWith(v, "the strands are short: median 30 mm where the hair spans 300 mm"));
  strands.median_length_mm = 10;
  EXPECT_STREQ(JudgeReconstruction(nullptr, &strands).name(), "failed");
  strands = SoundStrands();
  strands.views_measured = 0;
  EXPECT_TRUE(
      HasReasonWith(JudgeReconstruction(nullptr, &strands), "strands over skin not checked"));
  strands.strands = 0;
  EXPECT_STREQ(JudgeReconstruction(nullptr, &strands).name(), "failed");

  strands = SoundStrands();
  strands.samples_over_skin = 50;  // 5 %
  v = JudgeReconstruction(nullptr, &strands);
  EXPECT_STREQ(v.name(), "check");
  EXPECT_TRUE(HasReasonWith(v, "5.0 % of the strand samples facing a camera lie over skin"));
}

TEST(ReconstructionVerdict, OptionsOutOfRangeAreNamed) {
  EXPECT_TRUE(ReconstructionVerdictOptions{}.Check().ok());
  ReconstructionVerdictOptions o;
  o.max_over_skin_share = std::nan("");
  EXPECT_NE(o.Check().message().find("max_over_skin_share"), std::string::npos);
  o = {};
  o.failed_direction_agreement = 0.9;
  EXPECT_NE(o.Check().message().find("failed_direction_agreement"), std::string::npos);
}

// A camera on -y looking at the origin along +y; the head (label 2) fills
// the left half of the image, hair (3) the right half.
TEST(StrandPlausibility, CountsSamplesInFrontOfTheHeadOverSkin) {
  const std::string dir = ::testing::TempDir() + "/strand_plausibility";
  std::filesystem::create_directories(dir);
  ReconstructionView view;
  view.name = "000_CAM";
  view.camera.width_px = 200;
  view.camera.height_px = 100;
  view.camera.fx_px = view.camera.fy_px = 1000;
  view.camera.cx_px = 100;
  view.camera.cy_px = 50;
  // Camera axes: x = object x, y = object -z, z = object y; 1000 mm away.
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  view.cam_from_object = Rigid3d(r, Eigen::Vector3d(0, 0, 1000));
  cv::Mat1b label(100, 200, static_cast<uint8_t>(kSegHair));
  label(cv::Rect(0, 0, 100, 100)).setTo(kSegHead);
  ASSERT_TRUE(cv::imwrite(dir + "/000_CAM_label.png", label));

  StrandSet strands;
  // In front of the head's centre (y < 0), over the head's half (x < 0): 3 samples.
  for (float z : {-10.f, 0.f, 10.f}) strands.points_mm.emplace_back(-20.f, -50.f, z);
  // In front, over the hair's half: 3 samples.
  for (float z : {-10.f, 0.f, 10.f}) strands.points_mm.emplace_back(20.f, -50.f, z);
  // Behind the head's centre, over the head's half: hidden, not counted.
  for (float z : {-10.f, 0.f, 10.f}) strands.points_mm.emplace_back(-20.f, 50.f, z);
  // In front, 0.4 px left of the boundary's pixel centre (u = 99.6): the hair's pixel 100.
  strands.points_mm.emplace_back(-0.38f, -50.f, 0.f);
  strands.point_counts = {3, 3, 3, 1};
  std::vector<OrientedPoint> points(101);
  for (size_t i = 0; i < points.size(); ++i)
    points[i].position_mm = Eigen::Vector3f(0, 0, static_cast<float>(i) * 2.0f);  // 0..200 mm

  auto skin = SkinViews::Load({view}, dir, Eigen::Vector3d::Zero());
  ASSERT_TRUE(skin.ok()) << skin.status().ToString();
  auto s = MeasureStrandPlausibility(strands, points, &*skin, 1);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->strands, 4);
  EXPECT_DOUBLE_EQ(s->median_length_mm, 20.0);
  EXPECT_NEAR(s->hair_extent_mm, 192.0, 4.0);
  EXPECT_EQ(s->views_measured, 1);
  EXPECT_EQ(s->samples_facing, 7);
  EXPECT_EQ(s->samples_over_skin, 3);

  // Without the views' skin nothing is counted over skin, and the verdict says so.
  s = MeasureStrandPlausibility(strands, points, nullptr, 1);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->views_measured, 0);
  EXPECT_EQ(s->samples_facing, 0);
  EXPECT_TRUE(HasReasonWith(JudgeReconstruction(nullptr, &*s), "strands over skin not checked"));
  EXPECT_FALSE(MeasureStrandPlausibility(strands, points, &*skin, 0).ok());
}

}  // namespace
}  // namespace hairrig
