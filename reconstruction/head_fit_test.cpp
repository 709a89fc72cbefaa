// The head fit on the analytic subject of tests/support/head_scene_testing.h: the labels
// are exact, so the fit's errors are the method's own.
#include "reconstruction/head_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include "reconstruction/hair_segmentation.h"
#include "tests/support/head_scene_testing.h"

namespace hairrig {
namespace {

using head_scene::TrueHead;
using head_scene::Views;

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return RadToDeg(std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)));
}

void ExpectFits(const HeadSpec& truth, const HeadFitSummary& fit) {
  std::cout << fit.BriefReport();
  const HeadSpec& head = fit.head;
  EXPECT_LT((head.center_turntable_mm - truth.center_turntable_mm).norm(), 5.0);
  EXPECT_LT((head.radii_mm - truth.radii_mm).cwiseAbs().maxCoeff(), 8.0);
  EXPECT_TRUE(head.mesh_file.empty());
  EXPECT_TRUE(head.scalp.defined);
  EXPECT_FALSE(head.scalp.parting);
  EXPECT_TRUE(fit.face_measured);
  EXPECT_LT(AngleDeg(head.scalp.face_dir, truth.scalp.face_dir), 10.0);
  // The hairline is the typical one.
  EXPECT_EQ(head.scalp.hairline_front_deg, ScalpSpec{}.hairline_front_deg);
  EXPECT_EQ(head.scalp.hairline_nape_deg, ScalpSpec{}.hairline_nape_deg);
  EXPECT_LT(fit.inside_share, 0.01);
  EXPECT_GT(fit.skin_on_surface_share, 0.4);
}

TEST(HeadFit, FindsTheHeadAndItsScalpUnderTheHair) {
  const HeadSpec truth = TrueHead(Eigen::Vector3d(0, -1, 0));
  const Result<HeadFitSummary> fit = FitHeadToViews(Views(truth), HeadFitOptions{});
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  ExpectFits(truth, *fit);
}

TEST(HeadFit, FindsAFaceThatLooksAlongX) {
  const HeadSpec truth = TrueHead(Eigen::Vector3d(1, 0, 0));
  const Result<HeadFitSummary> fit = FitHeadToViews(Views(truth), HeadFitOptions{});
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  ExpectFits(truth, *fit);
}

TEST(HeadFit, RefusesViewsWithoutSkinAndBadInput) {
  const HeadSpec truth = TrueHead(Eigen::Vector3d(0, -1, 0));
  std::vector<HeadFitView> views = Views(truth);
  std::vector<HeadFitView> no_skin = views;
  for (HeadFitView& v : no_skin) v.label.setTo(kSegHair, v.label == kSegHead);
  const Result<HeadFitSummary> fit = FitHeadToViews(no_skin, HeadFitOptions{});
  ASSERT_EQ(fit.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(fit.status().message().find("give the subject's head"), std::string::npos);

  std::vector<HeadFitView> one(views.begin(), views.begin() + 1);
  EXPECT_EQ(FitHeadToViews(one, HeadFitOptions{}).status().code(), StatusCode::kInvalidArgument);
  std::vector<HeadFitView> wrong_size = views;
  wrong_size[3].label = cv::Mat1b(10, 10, uint8_t{0});
  const Result<HeadFitSummary> sized = FitHeadToViews(wrong_size, HeadFitOptions{});
  ASSERT_EQ(sized.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(sized.status().message().find("view 3"), std::string::npos);
  HeadFitOptions bad;
  bad.radii_sigma_mm = 0;
  EXPECT_EQ(FitHeadToViews(views, bad).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
