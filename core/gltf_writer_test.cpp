#include "core/gltf_writer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

uint32_t U32At(const std::vector<uint8_t>& b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// The JSON chunk and the binary chunk of a GLB, checking the container.
struct Glb {
  nlohmann::json doc;
  std::vector<uint8_t> bin;
};
Glb Parse(const std::vector<uint8_t>& bytes) {
  Glb glb;
  EXPECT_GE(bytes.size(), 28u);
  EXPECT_EQ(U32At(bytes, 0), 0x46546C67u);
  EXPECT_EQ(U32At(bytes, 4), 2u);
  EXPECT_EQ(U32At(bytes, 8), bytes.size());
  const uint32_t json_length = U32At(bytes, 12);
  EXPECT_EQ(U32At(bytes, 16), 0x4E4F534Au);
  EXPECT_EQ(json_length % 4, 0u);
  glb.doc = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_length);
  const size_t bin_at = 20 + json_length;
  EXPECT_EQ(U32At(bytes, bin_at + 4), 0x004E4942u);
  glb.bin.assign(bytes.begin() + static_cast<std::ptrdiff_t>(bin_at + 8), bytes.end());
  EXPECT_EQ(glb.bin.size(), U32At(bytes, bin_at));
  return glb;
}

// The floats of accessor `index` (tightly packed, as the writer lays them out).
std::vector<float> Floats(const Glb& glb, int index) {
  const nlohmann::json& accessor = glb.doc["accessors"][index];
  const nlohmann::json& view = glb.doc["bufferViews"][accessor["bufferView"].get<int>()];
  const size_t offset = view["byteOffset"], length = view["byteLength"];
  std::vector<float> out(length / 4);
  std::memcpy(out.data(), glb.bin.data() + offset, length);
  return out;
}

StrandSet TwoStrands() {
  StrandSet s;
  // A strand rising 100 mm above the origin, and one along +y at z = 50 mm.
  s.points_mm = {{0, 0, 0}, {0, 0, 50}, {0, 0, 100}, {0, 0, 50}, {0, 100, 50}};
  s.point_counts = {3, 2};
  return s;
}

TEST(GltfWriter, StrandsAreLinesInMetresWithYUp) {
  const StrandSet strands = TwoStrands();
  GltfScene scene;
  scene.strand_sets.push_back({.name = "strands", .strands = &strands});
  GltfWriteSummary summary;
  auto bytes = EncodeGlb(scene, &summary);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  const Glb glb = Parse(*bytes);
  EXPECT_EQ(glb.doc["asset"]["version"], "2.0");
  EXPECT_EQ(summary.strands, 2);
  EXPECT_EQ(summary.segments, 3);
  EXPECT_EQ(summary.vertices, 5);
  EXPECT_EQ(summary.bytes, static_cast<int64_t>(bytes->size()));
  const nlohmann::json& primitive = glb.doc["meshes"][0]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 1);  // LINES
  const nlohmann::json& position =
      glb.doc["accessors"][primitive["attributes"]["POSITION"].get<int>()];
  EXPECT_EQ(position["count"], 5);
  // (x, y, z) mm -> (x, z, -y) m: the top of the rising strand is 0.1 m up +y,
  // the tip of the other 0.1 m towards -z.
  EXPECT_EQ(position["max"], nlohmann::json({0.0, 0.1f, 0.0}));
  EXPECT_EQ(position["min"], nlohmann::json({0.0, 0.0, -0.1f}));
  const nlohmann::json& indices = glb.doc["accessors"][primitive["indices"].get<int>()];
  EXPECT_EQ(indices["count"], 6);
  EXPECT_EQ(indices["componentType"], 5125);
  const std::vector<float> ids = Floats(glb, primitive["attributes"]["_STRAND_ID"]);
  EXPECT_EQ(ids, std::vector<float>({0, 0, 0, 1, 1}));
  EXPECT_FALSE(primitive["attributes"].contains("COLOR_0"));
  for (const nlohmann::json& view : glb.doc["bufferViews"])
    EXPECT_EQ(view["byteOffset"].get<size_t>() % 4, 0u);
}

TEST(GltfWriter, AHeadMeshAndColouredStrands) {
  StrandSet strands = TwoStrands();
  strands.colors.assign(5, {200, 100, 50});
  TriangleMesh head;
  head.vertices_mm = {{0, 0, 0}, {100, 0, 0}, {0, 100, 0}};
  head.triangles = {{0, 1, 2}};
  GltfScene scene;
  scene.strand_sets.push_back({.name = "strands", .strands = &strands});
  scene.meshes.push_back({.name = "head", .mesh = &head});
  auto bytes = EncodeGlb(scene);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  const Glb glb = Parse(*bytes);
  ASSERT_EQ(glb.doc["scenes"][0]["nodes"].size(), 2u);
  const nlohmann::json& colour =
      glb.doc["accessors"]
             [glb.doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"].get<int>()];
  EXPECT_EQ(colour["type"], "VEC4");
  EXPECT_EQ(colour["normalized"], true);
  const nlohmann::json& primitive = glb.doc["meshes"][1]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 4);
  // The triangle lies in z = 0 (mm) facing +z: its normal in glTF is +y.
  EXPECT_EQ(Floats(glb, primitive["attributes"]["NORMAL"]),
            std::vector<float>({0, 1, 0, 0, 1, 0, 0, 1, 0}));
}

TEST(GltfWriter, AnAnimationShowsOneFrameAtATime) {
  StrandSet frame0 = TwoStrands(), frame1 = TwoStrands(), frame2 = TwoStrands();
  frame1.points_mm[2].x() = 10;
  frame2.points_mm[2].x() = 20;
  GltfScene scene;
  scene.animations.push_back(
      {.name = "head-shake", .frames = {&frame0, &frame1, &frame2}, .fps = 10});
  GltfWriteSummary summary;
  auto bytes = EncodeGlb(scene, &summary);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  EXPECT_EQ(summary.frames, 3);
  EXPECT_EQ(summary.vertices, 15);
  const Glb glb = Parse(*bytes);
  const nlohmann::json& animation = glb.doc["animations"][0];
  EXPECT_EQ(animation["name"], "head-shake");
  ASSERT_EQ(animation["channels"].size(), 3u);
  const nlohmann::json& sampler = animation["samplers"][1];
  EXPECT_EQ(sampler["interpolation"], "STEP");
  // A key per frame and one closing the last frame's interval (the animation lasts 0.3 s).
  EXPECT_EQ(Floats(glb, sampler["input"]), std::vector<float>({0.0f, 0.1f, 0.2f, 0.3f}));
  EXPECT_EQ(Floats(glb, sampler["output"]),
            std::vector<float>({0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(Floats(glb, animation["samplers"][2]["output"]),
            std::vector<float>({0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1}));
  const nlohmann::json& parent = glb.doc["nodes"][glb.doc["scenes"][0]["nodes"][0].get<int>()];
  ASSERT_EQ(parent["children"].size(), 3u);
  EXPECT_FALSE(glb.doc["nodes"][parent["children"][0].get<int>()].contains("scale"));
  EXPECT_EQ(glb.doc["nodes"][parent["children"][1].get<int>()]["scale"],
            nlohmann::json({0.0, 0.0, 0.0}));
  // The frames share their index and strand-id buffers.
  EXPECT_EQ(glb.doc["meshes"][0]["primitives"][0]["indices"],
            glb.doc["meshes"][2]["primitives"][0]["indices"]);
}

TEST(GltfWriter, AMorphTargetAnimationBlendsFromFrameZero) {
  StrandSet frame0 = TwoStrands(), frame1 = TwoStrands(), frame2 = TwoStrands();
  frame1.points_mm[2].x() = 10;
  frame2.points_mm[2].y() = 20;  // glTF's -z
  GltfScene scene;
  scene.animations.push_back({.name = "head-shake",
                              .frames = {&frame0, &frame1, &frame2},
                              .fps = 10,
                              .encoding = GltfAnimationEncoding::kMorphTargets});
  GltfWriteSummary summary;
  auto bytes = EncodeGlb(scene, &summary);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  EXPECT_EQ(summary.frames, 3);
  EXPECT_EQ(summary.vertices, 5) << "frame 0's vertices; the others are offsets";
  EXPECT_EQ(summary.segments, 3);
  const Glb glb = Parse(*bytes);
  ASSERT_EQ(glb.doc["nodes"].size(), 1u);
  EXPECT_EQ(glb.doc["nodes"][0]["name"], "head-shake");
  const nlohmann::json& mesh = glb.doc["meshes"][0];
  EXPECT_EQ(mesh["weights"], nlohmann::json({0.0, 0.0}));
  const nlohmann::json& targets = mesh["primitives"][0]["targets"];
  ASSERT_EQ(targets.size(), 2u);
  const std::vector<float> offsets1 = Floats(glb, targets[0]["POSITION"]);
  const std::vector<float> offsets2 = Floats(glb, targets[1]["POSITION"]);
  ASSERT_EQ(offsets1.size(), 15u);
  EXPECT_FLOAT_EQ(offsets1[6], 0.01f);   // point 2's x, 10 mm
  EXPECT_FLOAT_EQ(offsets2[8], -0.02f);  // point 2's glTF z from +20 mm y
  const nlohmann::json& bound = glb.doc["accessors"][targets[1]["POSITION"].get<int>()]["min"];
  EXPECT_NEAR(bound[2].get<double>(), -0.02, 1e-7) << "morph targets carry their bounds";
  const nlohmann::json& animation = glb.doc["animations"][0];
  const nlohmann::json& sampler = animation["samplers"][0];
  EXPECT_EQ(sampler["interpolation"], "LINEAR");
  EXPECT_EQ(animation["channels"][0]["target"]["path"], "weights");
  EXPECT_EQ(Floats(glb, sampler["input"]), std::vector<float>({0.0f, 0.1f, 0.2f, 0.3f}));
  // Two weights per key: frame 0 (none), frame 1, frame 2, and frame 2 held to the end.
  EXPECT_EQ(Floats(glb, sampler["output"]), std::vector<float>({0, 0, 1, 0, 0, 1, 0, 1}));
}

TEST(GltfWriter, WispIdsArePerVertexWhereGiven) {
  const StrandSet strands = TwoStrands();
  const std::vector<uint32_t> wisps = {7, 3};
  GltfScene scene;
  scene.strand_sets.push_back({.name = "strands", .strands = &strands, .wisps = &wisps});
  scene.animations.push_back(
      {.name = "sim", .frames = {&strands, &strands}, .fps = 10, .wisps = &wisps});
  auto bytes = EncodeGlb(scene);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  const Glb glb = Parse(*bytes);
  for (const nlohmann::json& mesh : glb.doc["meshes"]) {
    const nlohmann::json& attributes = mesh["primitives"][0]["attributes"];
    ASSERT_TRUE(attributes.contains("_WISP_ID")) << mesh["name"];
    EXPECT_EQ(Floats(glb, attributes["_WISP_ID"]), std::vector<float>({7, 7, 7, 3, 3}));
  }
  // The frames share one wisp accessor.
  EXPECT_EQ(glb.doc["meshes"][1]["primitives"][0]["attributes"]["_WISP_ID"],
            glb.doc["meshes"][2]["primitives"][0]["attributes"]["_WISP_ID"]);
}

TEST(GltfWriter, APointCloudIsPointsInMetresWithYUp) {
  const std::vector<Eigen::Vector3f> points = {{10, 20, 30}, {-10, 0, 5}};
  const std::vector<std::array<uint8_t, 3>> colours = {{255, 0, 0}, {0, 255, 0}};
  GltfScene scene;
  scene.point_clouds.push_back({.name = "points", .points_mm = &points, .colours = &colours});
  GltfWriteSummary summary;
  auto bytes = EncodeGlb(scene, &summary);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  EXPECT_EQ(summary.vertices, 2);
  const Glb glb = Parse(*bytes);
  const nlohmann::json& primitive = glb.doc["meshes"][0]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 0);
  EXPECT_FALSE(primitive.contains("indices"));
  const std::vector<float> positions = Floats(glb, primitive["attributes"]["POSITION"]);
  const std::vector<float> expected = {0.010f, 0.030f, -0.020f, -0.010f, 0.005f, 0};
  ASSERT_EQ(positions.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(positions[i], expected[i], 1e-7f) << i;
  EXPECT_EQ(glb.doc["accessors"][primitive["attributes"]["COLOR_0"].get<int>()]["count"], 2);

  const std::vector<std::array<uint8_t, 3>> one_colour = {{1, 2, 3}};
  scene.point_clouds[0].colours = &one_colour;
  EXPECT_NE(EncodeGlb(scene).status().message().find("'points': 1 colours for 2 points"),
            std::string::npos);
  const std::vector<Eigen::Vector3f> none;
  scene.point_clouds[0].points_mm = &none;
  EXPECT_NE(EncodeGlb(scene).status().message().find("'points' is empty"), std::string::npos);
}

TEST(GltfWriter, BadInputIsNamed) {
  StrandSet strands = TwoStrands();
  GltfScene scene;
  scene.strand_sets.push_back({.name = "wig", .strands = &strands});
  auto message = [&] { return EncodeGlb(scene).status().message(); };
  strands.points_mm[1].y() = NAN;
  EXPECT_NE(message().find("'wig': point 1 is not finite"), std::string::npos) << message();
  strands = TwoStrands();
  strands.point_counts = {3, 3};
  EXPECT_NE(message().find("sum to 6, not its 5 points"), std::string::npos) << message();
  strands = TwoStrands();
  strands.colors.assign(2, {0, 0, 0});
  EXPECT_NE(message().find("2 colours for 5 points"), std::string::npos) << message();
  strands = TwoStrands();
  const std::vector<uint32_t> one_wisp = {0}, huge_wisp = {0, 1u << 24};
  scene.strand_sets[0].wisps = &one_wisp;
  EXPECT_NE(message().find("'wig': 1 wisp ids for 2 strands"), std::string::npos) << message();
  scene.strand_sets[0].wisps = &huge_wisp;
  EXPECT_NE(message().find("wisp id 16777216 is 2^24 or more"), std::string::npos) << message();

  StrandSet other = TwoStrands();
  other.point_counts = {2, 3};
  strands = TwoStrands();
  scene.strand_sets.clear();
  scene.animations.push_back({.name = "sim", .frames = {&strands, &other}, .fps = 30});
  EXPECT_NE(message().find("frame 1 has other strands than frame 0"), std::string::npos)
      << message();
  scene.animations[0].frames = {&strands};
  scene.animations[0].fps = 0;
  EXPECT_NE(message().find("fps must be positive"), std::string::npos) << message();

  TriangleMesh head;
  head.vertices_mm = {{0, 0, 0}};
  head.triangles = {{0, 1, 2}};
  scene.animations.clear();
  scene.meshes.push_back({.name = "head", .mesh = &head});
  EXPECT_NE(message().find("'head': a triangle indexes vertex 1 of 1"), std::string::npos)
      << message();
  EXPECT_NE(EncodeGlb(GltfScene{}).status().message().find("nothing to write"), std::string::npos);
  strands = TwoStrands();
  scene.meshes.clear();
  scene.strand_sets.push_back({.name = "wig", .strands = &strands});
  const auto unwritable = WriteGlb("/nonexistent-dir/x.glb", scene);
  EXPECT_EQ(unwritable.status().code(), StatusCode::kIoError);
  EXPECT_NE(unwritable.status().message().find("/nonexistent-dir/x.glb"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
