#include "core/calib_box.h"

#include <gtest/gtest.h>

#include <fstream>

namespace hairrig {
namespace {

TEST(CalibBox, DefaultBoxHasTagsFlatOnItsFaces) {
  auto box = LoadCalibBox("etc/calib-box.yaml");
  ASSERT_TRUE(box.ok()) << box.status().ToString();
  EXPECT_EQ(box->tags.size(), 24u);
  for (const BoxTag& tag : box->tags) {
    const BoxFace& face = box->faces[tag.face];
    for (const auto& corner : tag.corners_box_mm) {
      EXPECT_NEAR((corner - face.center_box_mm).dot(face.normal_box), 0.0, 1e-12);
    }
    EXPECT_NEAR((tag.corners_box_mm[1] - tag.corners_box_mm[0]).norm(), tag.size_mm, 1e-9);
    // Corner order winds so that (p1-p0) x (p3-p0) points out of the face... or in:
    // seen from outside, bottom-left -> bottom-right -> top-right is counter-clockwise.
    const Eigen::Vector3d n = (tag.corners_box_mm[1] - tag.corners_box_mm[0])
                                  .cross(tag.corners_box_mm[2] - tag.corners_box_mm[1]);
    EXPECT_GT(n.dot(face.normal_box), 0.0);
  }
  EXPECT_NE(box->FindTag(23), nullptr);
  EXPECT_EQ(box->FindTag(99), nullptr);
}

TEST(CalibBox, FaceFramesAreRightHandedWithOutwardNormals) {
  for (const BoxFace& f : MakeBoxFaces({200, 150, 100})) {
    EXPECT_LT((f.right_box.cross(f.down_box) + f.normal_box).norm(), 1e-12) << f.name;
  }
}

std::string WriteTemp(const std::string& text) {
  const std::string path = ::testing::TempDir() + "/box.yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(CalibBox, BadBoxesAreRefusedWithTheField) {
  const std::string head =
      "size_mm: [200, 200, 200]\ntag_size_mm: 72\nfaces:\n  - name: \"+x\"\n    tags:\n";
  auto dup = LoadCalibBox(WriteTemp(
      head + "      - {id: 1, center_mm: [-48, 0]}\n      - {id: 1, center_mm: [48, 0]}\n"));
  EXPECT_NE(dup.status().message().find("used twice"), std::string::npos)
      << dup.status().ToString();
  auto off = LoadCalibBox(WriteTemp(head + "      - {id: 1, center_mm: [90, 0]}\n"));
  EXPECT_NE(off.status().message().find("does not fit"), std::string::npos)
      << off.status().ToString();
  auto face =
      LoadCalibBox(WriteTemp("size_mm: [200, 200, 200]\nfaces:\n  - name: top\n    tags: []\n"));
  EXPECT_NE(face.status().message().find("faces[0].name"), std::string::npos)
      << face.status().ToString();
}

// A box as built written and read back: the same corners (to the file's 0.1
// um) and standard deviations; build errors beyond a hand-built box refused.
TEST(CalibBox, AsBuiltBoxRoundTripsThroughItsFile) {
  auto drawn = LoadCalibBox("etc/calib-box.yaml");
  ASSERT_TRUE(drawn.ok()) << drawn.status().ToString();
  CalibBox built = BuildBoxWithErrors(*drawn, {0.7, 1.0, 0.5, 0.3}, 3);
  built.tags[2].center_sd_mm = {0.02, 0.03};
  built.tags[2].turn_sd_deg = 0.04;
  built.faces[1].offset_sd_mm = 0.05;
  EXPECT_FALSE(built.AsDrawn());
  EXPECT_TRUE(drawn->AsDrawn());
  const std::string path = ::testing::TempDir() + "/box_as_built.yaml";
  ASSERT_TRUE(WriteCalibBox(built, path, "a test box\nsecond line").ok());
  auto read = LoadCalibBox(path);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_EQ(read->tags.size(), built.tags.size());
  for (size_t t = 0; t < built.tags.size(); ++t) {
    const BoxTag* back = read->FindTag(built.tags[t].id);
    ASSERT_NE(back, nullptr);
    for (size_t k = 0; k < 4; ++k)
      EXPECT_LT((back->corners_box_mm[k] - built.tags[t].corners_box_mm[k]).norm(), 1e-3)
          << "tag " << built.tags[t].id << " corner " << k;
  }
  EXPECT_NEAR(read->FindTag(built.tags[2].id)->center_sd_mm.y(), 0.03, 1e-9);
  EXPECT_NEAR(read->FindTag(built.tags[2].id)->turn_sd_deg, 0.04, 1e-9);
  EXPECT_NEAR(read->faces[1].offset_sd_mm, 0.05, 1e-9);
  // The tags moved, turned and tilted: their corners are off the drawing, their size kept.
  const BoxTag& a = built.tags[0];
  const BoxTag& b = *drawn->FindTag(a.id);
  EXPECT_GT((a.corners_box_mm[0] - b.corners_box_mm[0]).norm(), 1e-3);
  EXPECT_NEAR((a.corners_box_mm[1] - a.corners_box_mm[0]).norm(), a.size_mm, 1e-9);
  auto far = LoadCalibBox(
      WriteTemp("size_mm: [200, 200, 200]\ntag_size_mm: 72\nfaces:\n  - name: \"+x\"\n    "
                "offset_mm: 25\n    tags:\n      - {id: 1, center_mm: [0, 0]}\n"));
  EXPECT_NE(far.status().message().find("offset_mm"), std::string::npos) << far.status().ToString();
}

}  // namespace
}  // namespace hairrig
