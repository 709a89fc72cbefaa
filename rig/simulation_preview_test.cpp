#include "rig/simulation_preview.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

class CountingPreviewer : public StrandPreviewer {
 public:
  Result<cv::Mat> Draw(const StrandSet& strands) override {
    return cv::Mat(2, 3, CV_8UC3, cv::Scalar::all(static_cast<double>(strands.num_strands())));
  }
};

// One test, so that the order of the two states is fixed.
TEST(StrandPreview, NoneUntilRegisteredThenTheRegisteredFactoryWithItsArguments) {
  auto none = MakeStrandPreviewer("scene.yaml", HeadSpec{});
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(none.status().message().find("--preview-every 0"), std::string::npos)
      << none.status().message();

  std::string seen_scene;
  Eigen::Vector3d seen_radii = Eigen::Vector3d::Zero();
  RegisterStrandPreviewer([&](const std::string& scene_file, const HeadSpec& head) {
    seen_scene = scene_file;
    seen_radii = head.radii_mm;
    return Result<std::unique_ptr<StrandPreviewer>>(std::make_unique<CountingPreviewer>());
  });
  HeadSpec head;
  head.radii_mm = {70, 80, 90};
  auto made = MakeStrandPreviewer("scenes/small.yaml", head);
  ASSERT_TRUE(made.ok()) << made.status().ToString();
  EXPECT_EQ(seen_scene, "scenes/small.yaml");
  EXPECT_EQ(seen_radii, Eigen::Vector3d(70, 80, 90));
  StrandSet strands;
  strands.AddStrand({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 0, 1)});
  auto image = (*made)->Draw(strands);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image->at<cv::Vec3b>(0, 0)[0], 1);
}

}  // namespace
}  // namespace hairrig
