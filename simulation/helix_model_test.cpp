#include "simulation/helix_model.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/file_util.h"

namespace hairrig {
namespace {

StrandSet Curls() {
  StrandSet set;
  for (int s = 0; s < 12; ++s) {
    std::vector<Eigen::Vector3f> p;
    for (int k = 0; k < 80; ++k) {
      const float a = 0.25f * static_cast<float>(k);
      p.emplace_back(20.0f * static_cast<float>(s % 4) + 5 * std::cos(a),
                     20.0f * static_cast<float>(s / 4) + 5 * std::sin(a),
                     -0.6f * static_cast<float>(k));
    }
    set.AddStrand(p);
  }
  return set;
}

TEST(HelixModel, FitWriteReadRoundTrip) {
  FitOptions o;
  o.guides.num_guides = 4;
  FitSummary s;
  auto model = FitHairModel(Curls(), o, &s);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  EXPECT_EQ(s.guides, 4);
  EXPECT_LT(s.mean_error_mm, 0.5);
  const std::string path = ::testing::TempDir() + "/model.json";
  ASSERT_TRUE(WriteHelixModel(path, *model, s).ok());
  auto read = ReadHelixModel(path);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_EQ(read->guides.size(), model->guides.size());
  for (size_t g = 0; g < read->guides.size(); ++g) {
    const auto& a = model->guides[g].elements.back();
    const auto& b = read->guides[g].elements.back();
    EXPECT_NEAR((a.PointAt(a.length_mm) - b.PointAt(b.length_mm)).norm(), 0, 1e-9);
  }
}

TEST(HelixModel, BadModelsAreRefusedWithTheReason) {
  const std::string dir = ::testing::TempDir();
  ASSERT_TRUE(WriteFileAtomic(dir + "/v2.json",
                              R"({"format": "hairrig-helix-model", "version": 2, "guides": []})")
                  .ok());
  auto r = ReadHelixModel(dir + "/v2.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("version 2"), std::string::npos) << r.status().ToString();
  ASSERT_TRUE(WriteFileAtomic(dir + "/nan.json",
                              R"({"format": "hairrig-helix-model", "version": 1, "guides":
      [{"strand": 0, "elements": [{"start_mm": [0, 0, 0], "start_tangent": [1, 0, 0],
        "darboux_per_mm": [0, 0, 0], "length_mm": -1}]}]})")
                  .ok());
  r = ReadHelixModel(dir + "/nan.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("guides[0].elements[0]"), std::string::npos)
      << r.status().ToString();
  ASSERT_TRUE(WriteFileAtomic(dir + "/other.json", "{\"hello\": 1}").ok());
  EXPECT_FALSE(ReadHelixModel(dir + "/other.json").ok());
}

// A mistyped field gives CorruptData naming the file and the field (a string
// cluster_of_strand used to end in std::terminate).
TEST(HelixModel, MistypedFieldsAreNamed) {
  const std::string dir = ::testing::TempDir();
  const std::string element =
      R"({"start_mm": [0, 0, 0], "start_tangent": [1, 0, 0], "darboux_per_mm": [0, 0, 0], "length_mm": 1})";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"("guides": [{"strand": 0, "elements": [E]}], "cluster_of_strand": "abc")",
       "field 'cluster_of_strand'"},
      {R"("guides": [{"strand": 0, "elements": [E]}], "cluster_of_strand": [0, 1])",
       "field 'cluster_of_strand': item 1"},
      {R"("guides": [{"strand": "x", "elements": [E]}])", "field 'guides[0].strand'"},
      {R"("guides": {"a": 1})", "field 'guides'"},
      {R"("guides": [{"elements": [3]}])", "field 'guides[0].elements[0]'"},
      {R"("guides": [{"elements": [E]}], "source": 7)", "field 'source'"},
  };
  for (const auto& [fields, expected] : cases) {
    std::string text = R"({"format": "hairrig-helix-model", "version": 1, )" + fields + "}";
    const size_t at = text.find('E');
    if (at != std::string::npos && text.compare(at - 1, 3, "[E]") == 0)
      text.replace(at, 1, element);
    ASSERT_TRUE(WriteFileAtomic(dir + "/typed.json", text).ok());
    const auto r = ReadHelixModel(dir + "/typed.json");
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
    EXPECT_NE(r.status().message().find(dir + "/typed.json: " + expected), std::string::npos)
        << r.status().ToString();
  }
}

TEST(HelixModel, DegenerateStrandsAreNamed) {
  StrandSet set = Curls();
  set.AddStrand({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}});  // zero length
  FitOptions o;
  o.guides.num_guides = 13;  // every strand a guide
  auto model = FitHairModel(set, o, nullptr);
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.status().message().find("strand 12: fewer than 2 distinct points"),
            std::string::npos)
      << model.status().ToString();
}

// A zero-length strand among others is named by its own index, whichever
// guide it becomes, with the guides chosen by the target RMS.
TEST(HelixModel, AZeroLengthGuideIsNamedByItsStrandIndex) {
  StrandSet set;
  const StrandSet curls = Curls();
  const auto offsets = curls.Offsets();
  for (size_t s = 0; s < 5; ++s) {
    set.AddStrand(
        std::vector<Eigen::Vector3f>(curls.points_mm.begin() + static_cast<long>(offsets[s]),
                                     curls.points_mm.begin() + static_cast<long>(offsets[s + 1])));
  }
  set.AddStrand({{500, 500, 0}, {500, 500, 0}});  // strand 5, far from the others: its own guide
  FitOptions o;
  o.guides.target_rms_mm = 1;
  auto model = FitHairModel(set, o, nullptr);
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.status().message().find("strand 5: fewer than 2 distinct points"),
            std::string::npos)
      << model.status().ToString();
}

// Coordinates near float's largest (3.4e38), where differences between points
// overflow, are refused before the guides are chosen, naming the strand and
// the vertex, never a strand -1.
TEST(HelixModel, CoordinatesThatOverflowNameTheStrandAndVertex) {
  StrandSet set = Curls();
  set.points_mm[static_cast<size_t>(5 * 80 + 2)].x() = 3.4e38f;  // strand 5, vertex 2
  FitOptions o;
  o.guides.num_guides = 4;
  auto model = FitHairModel(set, o, nullptr);
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.status().message().find("strand 5 vertex 2"), std::string::npos)
      << model.status().ToString();
  EXPECT_EQ(model.status().message().find("strand -1"), std::string::npos)
      << model.status().ToString();
}

}  // namespace
}  // namespace hairrig
