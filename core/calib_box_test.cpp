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

}  // namespace
}  // namespace hairrig
