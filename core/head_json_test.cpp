#include "core/head_json.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

// A head whose every field differs from its default.
HeadSpec UnusualHead() {
  HeadSpec h;
  h.mesh_file = "/somewhere/heads/mannequin.ply";
  h.turntable_from_mesh =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
              Eigen::Vector3d(4, -5, 260));
  h.center_turntable_mm = Eigen::Vector3d(1, -2, 240);
  h.radii_mm = Eigen::Vector3d(70, 90, 110);
  h.albedo = Eigen::Vector3d(0.5, 0.4, 0.3);
  ScalpSpec& s = h.scalp;
  s.defined = true;
  s.center_turntable_mm = Eigen::Vector3d(0, 3, 320);
  s.face_dir = Eigen::Vector3d(1, -1, 0).normalized();
  s.hairline_front_deg = 35;
  s.hairline_temple_deg = 21;
  s.hairline_ear_deg = 6;
  s.hairline_nape_deg = -20;
  s.parting = false;
  s.parting_offset_deg = -12;
  s.parting_width_mm = 3.5;
  s.parting_back_deg = 15;
  return h;
}

TEST(HeadJson, EveryFieldSurvivesARoundTripWithTheMeshBesideTheFile) {
  const HeadSpec h = UnusualHead();
  // Through text, as a file holds it.
  const nlohmann::json j = nlohmann::json::parse(HeadSpecToJson(h, "head_mesh.ply").dump(1));
  auto back = HeadSpecFromJson(j, "/captures/c1/ground_truth", "ground_truth.json: head");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->mesh_file, "/captures/c1/ground_truth/head_mesh.ply");
  EXPECT_LT(RotationDifferenceDeg(back->turntable_from_mesh, h.turntable_from_mesh), 1e-9);
  EXPECT_LT((back->turntable_from_mesh.translation - h.turntable_from_mesh.translation).norm(),
            1e-12);
  EXPECT_EQ(back->center_turntable_mm, h.center_turntable_mm);
  EXPECT_EQ(back->radii_mm, h.radii_mm);
  EXPECT_EQ(back->albedo, h.albedo);
  const ScalpSpec &a = back->scalp, &b = h.scalp;
  EXPECT_EQ(a.defined, b.defined);
  EXPECT_EQ(a.center_turntable_mm, b.center_turntable_mm);
  EXPECT_EQ(a.face_dir, b.face_dir);
  EXPECT_EQ(a.hairline_front_deg, b.hairline_front_deg);
  EXPECT_EQ(a.hairline_temple_deg, b.hairline_temple_deg);
  EXPECT_EQ(a.hairline_ear_deg, b.hairline_ear_deg);
  EXPECT_EQ(a.hairline_nape_deg, b.hairline_nape_deg);
  EXPECT_EQ(a.parting, b.parting);
  EXPECT_EQ(a.parting_offset_deg, b.parting_offset_deg);
  EXPECT_EQ(a.parting_width_mm, b.parting_width_mm);
  EXPECT_EQ(a.parting_back_deg, b.parting_back_deg);
}

TEST(HeadJson, AnEllipsoidHeadHasNoMeshAndAnAbsolutePathStaysAsItIs) {
  HeadSpec ellipsoid;
  const nlohmann::json j = HeadSpecToJson(ellipsoid, "ignored.ply");
  EXPECT_FALSE(j.contains("mesh_file"));
  EXPECT_FALSE(j.contains("turntable_from_mesh"));
  auto back = HeadSpecFromJson(j, "/base", "head");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_TRUE(back->mesh_file.empty());
  EXPECT_FALSE(back->scalp.defined);

  auto absolute = HeadSpecFromJson(HeadSpecToJson(UnusualHead(), "/meshes/m.obj"), "/base", "head");
  ASSERT_TRUE(absolute.ok()) << absolute.status().ToString();
  EXPECT_EQ(absolute->mesh_file, "/meshes/m.obj");
}

TEST(HeadJson, ADamagedHeadIsCorruptDataNamingTheFileAndTheField) {
  const nlohmann::json good = HeadSpecToJson(UnusualHead(), "head_mesh.ply");
  const auto expect_corrupt = [](const nlohmann::json& j, const std::string& field) {
    auto head = HeadSpecFromJson(j, "/base", "gt.json: head");
    ASSERT_FALSE(head.ok()) << field;
    EXPECT_EQ(head.status().code(), StatusCode::kCorruptData) << head.status().ToString();
    EXPECT_NE(head.status().message().find("gt.json: head"), std::string::npos)
        << head.status().message();
    EXPECT_NE(head.status().message().find(field), std::string::npos) << head.status().message();
  };
  nlohmann::json j = good;
  j["radii_mm"] = {70, 0, 110};
  expect_corrupt(j, "radii_mm");
  j = good;
  j["scalp"].erase("hairline_ear_deg");
  expect_corrupt(j, "field 'scalp.hairline_ear_deg'");
  j = good;
  j["scalp"]["parting"] = "yes";
  expect_corrupt(j, "parting");
  j = good;
  j["turntable_from_mesh"]["quaternion_wxyz"] = {2, 0, 0, 0};
  expect_corrupt(j, "turntable_from_mesh");
  j = good;
  j["mesh_file"] = 3;
  expect_corrupt(j, "mesh_file");
  expect_corrupt(nlohmann::json::array(), "head");
}

}  // namespace
}  // namespace hairrig
