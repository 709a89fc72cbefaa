#include "core/head_config.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string WriteFile(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path.string();
}

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hairrig_head_config_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(HeadConfig, AHeadSectionIsAMapOrTheNameOfAHeadFileWithPathsBesideIt) {
  const fs::path dir = TempDir("forms");
  WriteFile(dir / "heads/h.yaml",
            "head:\n  mesh: meshes/m.ply\n  center_mm: [1, 2, 300]\n  radii_mm: [70, 90, 100]\n"
            "  scalp: {hairline_front_deg: 30, parting: false}\n");
  const std::string rig =
      WriteFile(dir / "rig.yaml", "by_file: heads/h.yaml\ninline: {radii_mm: [60, 70, 80]}\n");
  auto root = ConfigNode::LoadFile(rig);
  ASSERT_TRUE(root.ok());
  HeadSpec by_file, inline_head;
  ASSERT_TRUE(ReadHeadConfig(*root, "by_file", rig, &by_file).ok());
  EXPECT_EQ(by_file.mesh_file, (dir / "heads/meshes/m.ply").lexically_normal().string());
  EXPECT_EQ(by_file.center_turntable_mm, Eigen::Vector3d(1, 2, 300));
  EXPECT_TRUE(by_file.scalp.defined);
  EXPECT_FALSE(by_file.scalp.parting);
  EXPECT_DOUBLE_EQ(by_file.scalp.hairline_front_deg, 30);
  ASSERT_TRUE(ReadHeadConfig(*root, "inline", rig, &inline_head).ok());
  EXPECT_TRUE(inline_head.mesh_file.empty());
  EXPECT_EQ(inline_head.radii_mm, Eigen::Vector3d(60, 70, 80));
  EXPECT_FALSE(inline_head.scalp.defined);
}

TEST(HeadConfig, AWrittenHeadFileReadsBackAsTheSameHead) {
  const fs::path dir = TempDir("write");
  HeadSpec head;
  head.mesh_file = (dir / "it's here.ply").string();
  head.turntable_from_mesh = Rigid3d(Eigen::AngleAxisd(DegToRad(-90), Eigen::Vector3d::UnitY()) *
                                         Eigen::AngleAxisd(DegToRad(20), Eigen::Vector3d::UnitX()),
                                     Eigen::Vector3d(121, -140, 180));
  head.center_turntable_mm = Eigen::Vector3d(1.25, -3.5, 312.75);
  head.radii_mm = Eigen::Vector3d(77, 96.5, 108);
  head.scalp.defined = true;
  head.scalp.center_turntable_mm = Eigen::Vector3d(0, 4, 320);
  head.scalp.face_dir = Eigen::Vector3d(0.6, -0.8, 0);
  head.scalp.hairline_front_deg = 31.5;
  head.scalp.hairline_nape_deg = -27.25;
  head.scalp.parting = false;
  const std::string path = (dir / "head.yaml").string();
  ASSERT_TRUE(WriteHeadFile(path, head).ok());
  const Result<HeadSpec> back = LoadHeadFile(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->mesh_file, head.mesh_file);
  EXPECT_TRUE(back->turntable_from_mesh.RotationMatrix().isApprox(
      head.turntable_from_mesh.RotationMatrix(), 1e-4));
  EXPECT_TRUE(back->turntable_from_mesh.translation.isApprox(head.turntable_from_mesh.translation));
  EXPECT_TRUE(back->center_turntable_mm.isApprox(head.center_turntable_mm));
  EXPECT_TRUE(back->radii_mm.isApprox(head.radii_mm));
  EXPECT_TRUE(back->scalp.defined);
  EXPECT_TRUE(back->scalp.face_dir.isApprox(head.scalp.face_dir));
  EXPECT_DOUBLE_EQ(back->scalp.hairline_front_deg, 31.5);
  EXPECT_DOUBLE_EQ(back->scalp.hairline_nape_deg, -27.25);
  EXPECT_DOUBLE_EQ(back->scalp.hairline_ear_deg, head.scalp.hairline_ear_deg);
  EXPECT_FALSE(back->scalp.parting);

  EXPECT_EQ(WriteHeadFile((dir / "no/such/folder/head.yaml").string(), head).code(),
            StatusCode::kIoError);
}

TEST(HeadConfig, ErrorsNameTheFileAndTheField) {
  const fs::path dir = TempDir("errors");
  const std::string bad = WriteFile(dir / "bad.yaml", "head:\n  radii_mm: [70, -1, 100]\n");
  auto head = LoadHeadFile(bad);
  ASSERT_FALSE(head.ok());
  EXPECT_NE(head.status().message().find("bad.yaml"), std::string::npos) << head.status().message();
  EXPECT_NE(head.status().message().find("radii_mm"), std::string::npos) << head.status().message();

  const std::string typo =
      WriteFile(dir / "typo.yaml", "head:\n  scalp: {hairline_frnt_deg: 30}\n");
  head = LoadHeadFile(typo);
  ASSERT_FALSE(head.ok());
  EXPECT_NE(head.status().message().find("hairline_frnt_deg"), std::string::npos)
      << head.status().message();

  const std::string rig = WriteFile(dir / "rig.yaml", "head: missing.yaml\n");
  auto root = ConfigNode::LoadFile(rig);
  ASSERT_TRUE(root.ok());
  HeadSpec spec;
  const Status missing = ReadHeadConfig(*root, "head", rig, &spec);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("missing.yaml"), std::string::npos) << missing.message();
  EXPECT_NE(missing.message().find("rig.yaml"), std::string::npos) << missing.message();
}

}  // namespace
}  // namespace hairrig
