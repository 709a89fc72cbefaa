// The reconstruction's per-view stages on a rendered view of the default
// scene against its ground-truth maps: orientation maps (the front-most
// strand's 2D direction on hair pixels) and hair segmentation.
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/core.hpp>

#include "core/calib_box.h"
#include "reconstruction/evaluation.h"
#include "reconstruction/hair_segmentation.h"
#include "reconstruction/orientation_map.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/renderer.h"
#include "sim_hw/scene_variations.h"
#include "tests/support/default_scene.h"

namespace hairrig {
namespace {

TEST(RenderedOrientation, DefaultViewAgainstTheTrueStrandDirections) {
  auto renderer = Renderer::Create(hairrig_test::DefaultScene());
  ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
  RenderOptions o;
  o.ground_truth = true;
  auto view = (*renderer)->Render(0, 75.79, o);  // the front of the wig, upper camera
  ASSERT_TRUE(view.ok());
  const cv::Mat hair = view->truth.label == ViewTruthMaps::kHair;
  OrientationOptions paper;
  paper.quadrature = false;
  paper.refinement_passes = 2;
  for (const auto& [name, options] :
       {std::pair<const char*, OrientationOptions>{"default", OrientationOptions{}},
        std::pair<const char*, OrientationOptions>{"even kernel, 2 refinements", paper}}) {
    auto map = ComputeOrientationMap(view->image, hair, options);
    ASSERT_TRUE(map.ok());
    auto accuracy = MeasureOrientation(*map, view->truth.orientation_deg, hair, 0.0);
    ASSERT_TRUE(accuracy.ok());
    std::printf("%s: %d hair pixels, median error %.2f deg, 90th percentile %.2f deg\n", name,
                accuracy->hair_pixels, accuracy->median_error_deg, accuracy->p90_error_deg);
    EXPECT_GT(accuracy->hair_pixels, 100000);
    if (std::string(name) == "default") {
      // Measured 7.6-7.9 deg (median) and 42-43 deg (90th percentile) on this view.
      EXPECT_LT(accuracy->median_error_deg, 10.0);
      EXPECT_LT(accuracy->p90_error_deg, 50.0);
    }
  }
}

TEST(RenderedSegmentation, DefaultViewsAgainstTheTrueLabels) {
  const Scene& scene = hairrig_test::DefaultScene();
  auto renderer = Renderer::Create(scene);
  ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
  const auto corners = BoxCornerPoints(0.5 * scene.box.size_mm);
  const std::vector<Eigen::Vector3d> box_corners(corners.begin(), corners.end());
  for (int view : {0, 3, 8}) {
    const ViewGroundTruth truth = MakeViewGroundTruth(scene, view);
    RenderOptions o;
    o.ground_truth = true;
    auto rendered = (*renderer)->Render(truth.camera_index, truth.turntable_deg, o);
    ASSERT_TRUE(rendered.ok());
    const auto outline = ProjectedOutline(truth.intrinsics, truth.cam_from_box, box_corners);
    ASSERT_GE(outline.size(), 4u);
    auto segmentation = SegmentHair(rendered->image, {outline}, SegmentationOptions{});
    ASSERT_TRUE(segmentation.ok()) << segmentation.status().ToString();
    const cv::Mat hair = segmentation->label == kSegHair;
    const cv::Mat true_hair = rendered->truth.label == ViewTruthMaps::kHair;
    const cv::Mat box = segmentation->label == kSegBox;
    const cv::Mat true_box = rendered->truth.label == ViewTruthMaps::kBox;
    const double hair_iou = *MaskIoU(hair, true_hair);
    const double box_iou = *MaskIoU(box, true_box);
    const double backdrop_iou = *MaskIoU(segmentation->label == kSegBackdrop,
                                         rendered->truth.label == ViewTruthMaps::kBackdrop);
    std::printf("view %d: IoU hair %.3f, box %.3f, backdrop %.3f\n", view, hair_iou, box_iou,
                backdrop_iou);
    // Measured on the demo capture's 38 views (hairrig_segmentation_bench):
    // hair IoU 0.87 mean, 0.74 worst (skin seen between strands over the neck
    // taken for hair); the backdrop and box are keyed well.
    EXPECT_GT(hair_iou, 0.6) << "view " << view;
    EXPECT_GT(box_iou, 0.95) << "view " << view;
    EXPECT_GT(backdrop_iou, 0.98) << "view " << view;
  }
}

// The share of `region` that `seg` labels hair.
double HairShareOf(const HairSegmentation& seg, const cv::Mat& region) {
  return cv::countNonZero((seg.label == kSegHair) & region) /
         static_cast<double>(cv::countNonZero(region));
}

TEST(RenderedSegmentation, APathTracersGrainIsNotTakenForHair) {
  // Blond curls on a white mannequin under a path tracer's grain: noise
  // alone gives the smooth mannequin hair's texture.
  auto scene = LoadScene("etc/scenes/curly_blond.yaml");
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  ASSERT_TRUE(ApplySceneVariations({"path_traced"}, &*scene).ok());
  auto renderer = Renderer::Create(*scene);
  ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
  const auto corners = BoxCornerPoints(0.5 * scene->box.size_mm);
  const ViewGroundTruth truth = MakeViewGroundTruth(*scene, 9);  // the face, lower camera
  RenderOptions o;
  o.ground_truth = true;
  o.noise_seed = 9;
  auto rendered = (*renderer)->Render(truth.camera_index, truth.turntable_deg, o);
  ASSERT_TRUE(rendered.ok()) << rendered.status().ToString();
  const std::vector<std::vector<cv::Point2f>> box = {
      ProjectedOutline(truth.intrinsics, truth.cam_from_box, {corners.begin(), corners.end()})};
  SegmentationOptions noise_kept;
  noise_kept.texture_less_noise = false;
  auto less_noise = SegmentHair(rendered->image, box, SegmentationOptions{});
  auto with_noise = SegmentHair(rendered->image, box, noise_kept);
  ASSERT_TRUE(less_noise.ok()) << less_noise.status().ToString();
  ASSERT_TRUE(with_noise.ok()) << with_noise.status().ToString();
  const cv::Mat skin = rendered->truth.label == ViewTruthMaps::kHead;
  const cv::Mat hair = rendered->truth.label == ViewTruthMaps::kHair;
  const double skin_as_hair = HairShareOf(*less_noise, skin);
  const double raw_skin_as_hair = HairShareOf(*with_noise, skin);
  std::printf(
      "path-traced view 9: skin taken for hair %.3f with the noise taken out of the "
      "texture, %.3f with it in; hair kept %.3f, %.3f\n",
      skin_as_hair, raw_skin_as_hair, HairShareOf(*less_noise, hair),
      HairShareOf(*with_noise, hair));
  EXPECT_LT(skin_as_hair, 0.2);
  EXPECT_GT(HairShareOf(*less_noise, hair), 0.8);
  EXPECT_GT(raw_skin_as_hair, skin_as_hair + 0.3)
      << "with the grain counted as texture the mannequin looks like hair: the case this test "
         "is for";
}

TEST(RenderedSegmentation, ABlackFrameIsRefused) {
  const cv::Mat black(400, 300, CV_8UC3, cv::Scalar(0, 0, 0));
  auto segmentation = SegmentHair(black, {}, SegmentationOptions{});
  EXPECT_EQ(segmentation.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(segmentation.status().message().find("black frame"), std::string::npos)
      << segmentation.status().message();
}

}  // namespace
}  // namespace hairrig
