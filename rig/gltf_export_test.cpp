#include "rig/gltf_export.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/file_util.h"
#include "tests/support/strand_capture.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

using hairrig_test::Comb;
using hairrig_test::MakeStrandCapture;

TEST(DecimateStrands, KeepsEveryKthStrandAndItsTip) {
  const StrandSet d = DecimateStrands(Comb(100, 50), 30, 10);
  EXPECT_EQ(d.point_counts.size(), 25u);  // every 4th of 100
  for (const uint32_t c : d.point_counts) EXPECT_LE(c, 10u);
  // Every 6th point of 50 (0, 6, .., 48) and the tip (49).
  EXPECT_EQ(d.point_counts[0], 10u);
  EXPECT_EQ(d.points_mm[9].z(), 300.0f - 2.0f * 49);
  const StrandSet whole = DecimateStrands(Comb(3, 5), 10, 10);
  EXPECT_EQ(whole.points_mm, Comb(3, 5).points_mm);
}

TEST(GltfExport, StrandsHeadAndAnimationAtTwoLevels) {
  const std::string dir = MakeStrandCapture("gltf_export", 4);
  GltfExportOptions o;
  o.dir = dir;
  o.head_file = "etc/heads/mannequin.yaml";
  o.simulation_dir = dir + "/simulation/head-shake";
  o.display_strands = 20;
  o.display_points = 8;
  o.animation_strands = 10;
  const auto s = ExportCaptureGltf(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  std::printf("%s", s->BriefReport().c_str());
  EXPECT_EQ(s->full.path, dir + "/reconstruction/strands/hair.glb");
  EXPECT_EQ(s->display.path, dir + "/reconstruction/strands/hair.display.glb");
  EXPECT_EQ(s->head_source, "etc/heads/mannequin.yaml");
  // The full level: 100 strands, then the 10 animated (decimated) strands.
  EXPECT_EQ(s->full.strands, 110);
  EXPECT_EQ(s->full.frames, 4);
  EXPECT_EQ(s->display.strands, 30);
  EXPECT_LT(s->display.bytes, s->full.bytes);
  EXPECT_EQ(static_cast<int64_t>(fs::file_size(s->full.path)), s->full.bytes);
  EXPECT_TRUE(fs::exists(s->display.path));
  EXPECT_EQ(s->ToJson()["full"]["frames"], 4);
  EXPECT_EQ(s->guides, 0);
}

TEST(GltfExport, TheGuidesAreASecondAnimationInTheFullLevelOnly) {
  const std::string dir = MakeStrandCapture("gltf_export_guides", 4, /*guides=*/true);
  GltfExportOptions o;
  o.dir = dir;
  o.simulation_dir = dir + "/simulation/head-shake";
  o.animation_strands = 10;
  o.animation_encoding = GltfAnimationEncoding::kMorphTargets;
  const auto s = ExportCaptureGltf(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->guides, 5);
  EXPECT_EQ(s->full.strands, 100 + 10 + 5);
  EXPECT_EQ(s->full.frames, 8) << "4 frames of the strands and 4 of the guides";
  // Morph targets: each animation's frame 0 holds the vertices (10 strands of
  // 26 points: every 2nd of 50 and the tip; 5 guides of 10), not every frame.
  EXPECT_EQ(s->full.vertices, 100 * 50 + 10 * 26 + 5 * 10);
  EXPECT_EQ(s->display.frames, 4) << "the display level has the strands' animation only";
  EXPECT_EQ(s->display.strands, 100 + 10);

  // A guides/ folder that stops short is named.
  fs::remove(o.simulation_dir + "/guides/frame_0003.hair");
  const auto short_guides = ExportCaptureGltf(o);
  ASSERT_FALSE(short_guides.ok());
  EXPECT_NE(short_guides.status().message().find("3 guide frames for 4"), std::string::npos)
      << short_guides.status().ToString();
}

// The JSON chunk of a GLB file's bytes.
nlohmann::json GlbJson(const std::string& path) {
  const auto bytes = ReadFileBytes(path, 1 << 26);
  EXPECT_TRUE(bytes.ok()) << path;
  uint32_t length = 0;
  std::memcpy(&length, bytes->data() + 12, 4);
  return nlohmann::json::parse(bytes->begin() + 20, bytes->begin() + 20 + length);
}

// The _WISP_ID accessor's count on the mesh named `name`, or -1 without one.
int WispCount(const nlohmann::json& doc, const std::string& name) {
  for (const nlohmann::json& mesh : doc["meshes"]) {
    if (mesh["name"] != name) continue;
    const nlohmann::json& attributes = mesh["primitives"][0]["attributes"];
    if (!attributes.contains("_WISP_ID")) return -1;
    return doc["accessors"][attributes["_WISP_ID"].get<int>()]["count"];
  }
  return -1;
}

TEST(GltfExport, WispIdsComeFromTheFittedModel) {
  const std::string dir = MakeStrandCapture("gltf_export_wisps", 2);
  nlohmann::json clusters = nlohmann::json::array();
  for (int s = 0; s < 100; ++s) clusters.push_back(s / 20);  // 5 wisps of 20 strands
  ASSERT_TRUE(WriteFileAtomic(dir + "/simulation/model.json",
                              nlohmann::json{{"cluster_of_strand", clusters}}.dump())
                  .ok());
  GltfExportOptions o;
  o.dir = dir;
  o.simulation_dir = dir + "/simulation/head-shake";
  o.display_strands = 20;
  o.animation_strands = 10;
  const auto s = ExportCaptureGltf(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->wisps, 5);
  const nlohmann::json full = GlbJson(s->full.path), display = GlbJson(s->display.path);
  EXPECT_EQ(WispCount(full, "strands"), 100 * 50);
  EXPECT_EQ(WispCount(full, "head-shake_frame_0"), 10 * 26);
  EXPECT_EQ(WispCount(display, "strands"), 20 * 26);

  // A model of other strands gives no wisps, and the export goes on.
  clusters.erase(clusters.begin());
  ASSERT_TRUE(WriteFileAtomic(dir + "/simulation/model.json",
                              nlohmann::json{{"cluster_of_strand", clusters}}.dump())
                  .ok());
  const auto other = ExportCaptureGltf(o);
  ASSERT_TRUE(other.ok()) << other.status().ToString();
  EXPECT_EQ(other->wisps, 0);
  EXPECT_EQ(WispCount(GlbJson(other->full.path), "strands"), -1);
}

TEST(GltfExport, StrandsAndPointsHeldInMemoryAreNotReadAgain) {
  const std::string dir = MakeStrandCapture("gltf_export_inputs", 0);
  hairrig_test::AddPointsAndTruth(dir, 1000);
  const StrandSet strands = Comb(40, 10);
  OrientedPoint point;
  point.position_mm = {0, 0, 100};
  point.direction = {0, 0, 1};
  const std::vector<OrientedPoint> points(30, point);
  // The files say otherwise: the export must take what it is given.
  fs::remove(dir + "/reconstruction/strands/strands.ply");
  GltfExportOptions o;
  o.dir = dir;
  o.display_only = true;
  const auto s = ExportCaptureGltf(o, {.strands = &strands, .points = &points});
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->cloud_points, 30);
  EXPECT_EQ(s->display.strands, 40 + s->truth_strands);
}

TEST(GltfExport, TheDisplayLevelCarriesThePointsAndTheTruth) {
  const std::string dir = MakeStrandCapture("gltf_export_display", 0);
  hairrig_test::AddPointsAndTruth(dir, 1000);
  GltfExportOptions o;
  o.dir = dir;
  o.display_only = true;
  o.display_strands = 20;
  o.display_cloud = 300;
  const auto s = ExportCaptureGltf(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_TRUE(s->full.path.empty());
  EXPECT_EQ(s->cloud_points, 250);  // every 4th of 1,000
  EXPECT_EQ(s->truth_strands, 17);  // every 3rd of 50
  EXPECT_EQ(s->display.strands, 20 + 17);
  EXPECT_NE(s->BriefReport().find("250 oriented points"), std::string::npos) << s->BriefReport();
  EXPECT_EQ(DirectionColour(Eigen::Vector3f(0, 0, -1)), (std::array<uint8_t, 3>{0, 0, 255}));
  EXPECT_EQ(DirectionColour(Eigen::Vector3f(0.6f, -0.8f, 0)),
            (std::array<uint8_t, 3>{153, 204, 0}));

  // A reconstruction in another frame than the truth's: the truth is left out.
  ASSERT_TRUE(
      WriteFileAtomic(dir + "/reconstruction/summary.json", R"({"object_frame": "colmap world"})")
          .ok());
  const auto other_frame = ExportCaptureGltf(o);
  ASSERT_TRUE(other_frame.ok()) << other_frame.status().ToString();
  EXPECT_EQ(other_frame->truth_strands, 0);

  o.display_cloud = 0;  // no points asked for
  const auto without = ExportCaptureGltf(o);
  ASSERT_TRUE(without.ok()) << without.status().ToString();
  EXPECT_EQ(without->cloud_points, 0);
  o.display_cloud = -1;
  EXPECT_NE(ExportCaptureGltf(o).status().message().find("--display-cloud"), std::string::npos);
}

TEST(GltfExport, MissingInputIsNamed) {
  const std::string dir = ::testing::TempDir() + "/gltf_export_empty";
  fs::create_directories(dir);
  GltfExportOptions o;
  o.dir = dir;
  auto s = ExportCaptureGltf(o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("strands.ply"), std::string::npos) << s.status().ToString();

  o.dir = MakeStrandCapture("gltf_export_nosim", 0);
  o.simulation_dir = o.dir + "/simulation/head-shake";
  s = ExportCaptureGltf(o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("no frame_NNNN strand files"), std::string::npos)
      << s.status().ToString();
  o.display_points = 1;
  EXPECT_NE(ExportCaptureGltf(o).status().message().find("--display-points"), std::string::npos);

  // No head anywhere: exported without one, and the summary says so.
  o = {};
  o.dir = MakeStrandCapture("gltf_export_nohead", 0);
  s = ExportCaptureGltf(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_TRUE(s->head_source.empty());
  EXPECT_NE(s->BriefReport().find("no head"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
