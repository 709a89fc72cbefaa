#include "reconstruction/point_reconstruction.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

// One row of pixels: hair, head, box, backdrop the segmentation is unsure of
// (a thin wisp's coverage), backdrop it is sure of.
TEST(SilhouetteOf, BackdropTheSegmentationIsUnsureOfCarvesNothing) {
  HairSegmentation s;
  s.label = (cv::Mat1b(1, 5) << kSegHair, kSegHead, kSegBox, kSegBackdrop, kSegBackdrop);
  s.hair_alpha = (cv::Mat1f(1, 5) << 0.9f, 0.f, 0.f, 0.4f, 0.1f);
  const cv::Mat1b silhouette = SilhouetteOf(s, 0.25);
  EXPECT_EQ(silhouette(0, 0), kSilhouetteSubject);
  EXPECT_EQ(silhouette(0, 1), kSilhouetteSubject);
  EXPECT_EQ(silhouette(0, 2), kSilhouetteUnknown);
  EXPECT_EQ(silhouette(0, 3), kSilhouetteUnknown);
  EXPECT_EQ(silhouette(0, 4), kSilhouetteEmpty);
  // At 1 every backdrop pixel carves.
  EXPECT_EQ(SilhouetteOf(s, 1.0)(0, 3), kSilhouetteEmpty);
  // Without a coverage map the labels alone decide.
  s.hair_alpha = cv::Mat1f();
  EXPECT_EQ(SilhouetteOf(s, 0.25)(0, 3), kSilhouetteEmpty);
}

TEST(PointReconstructionOptions, AnUncertainAlphaOutOfRangeIsNamed) {
  PointReconstructionOptions o;
  EXPECT_TRUE(o.Check().ok());
  o.hull_uncertain_alpha = 0;
  EXPECT_NE(o.Check().message().find("hull_uncertain_alpha"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
