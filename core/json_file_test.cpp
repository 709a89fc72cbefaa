#include "core/json_file.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

using nlohmann::json;

TEST(JsonObject, ReadsTypedFields) {
  const json j = {{"serial", "CAM-1"},
                  {"view", 3},
                  {"angle_deg", 12.5},
                  {"ok", true},
                  {"pose", {{"t", {1, 2, 3}}}},
                  {"ids", {4, 5}},
                  {"frames", {{{"file", "a"}}, {{"file", "b"}}}}};
  JsonObject r(j, "f.json");
  EXPECT_EQ(r.String("serial"), "CAM-1");
  EXPECT_EQ(r.Integer("view", {.min = 0, .max = 10}), 3);
  EXPECT_EQ(r.Number("angle_deg"), 12.5);
  EXPECT_EQ(r.Number("view"), 3.0);  // an integer is a number
  EXPECT_TRUE(r.Bool("ok"));
  EXPECT_EQ(r.Object("pose").Numbers("t", 3), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(r.IntegersOr("ids"), (std::vector<int64_t>{4, 5}));
  EXPECT_EQ(r.IntegersOr("absent"), std::vector<int64_t>{});
  EXPECT_EQ(r.StringOr("absent", "x"), "x");
  EXPECT_EQ(r.Objects("frames").at(1).String("file"), "b");
  EXPECT_TRUE(r.ok()) << r.status().ToString();
}

// Each mistake gives CorruptData naming the record and the field, never an exception.
TEST(JsonObject, ErrorsNameTheRecordAndTheField) {
  const json j = json::parse(R"({"view": -1, "bytes": 2.5, "sha256": 5, "big": 18446744073709551615,
                                 "pose": {"t": [1, "x", 3]}, "frames": [{"file": 1}], "list": "no"})");
  const std::vector<std::pair<std::function<void(const JsonObject&)>, std::string>> cases = {
      {[](const JsonObject& r) { r.Integer("view", {.min = 0}); },
       "field 'view': expected an integer >= 0, got -1"},
      {[](const JsonObject& r) { r.Integer("bytes"); },
       "field 'bytes': expected an integer, got 2.5"},
      {[](const JsonObject& r) { r.String("sha256"); }, "field 'sha256': expected a string, got 5"},
      {[](const JsonObject& r) { r.String("serial"); }, "field 'serial': is missing"},
      {[](const JsonObject& r) { r.Integer("big"); }, "field 'big': expected an integer"},
      {[](const JsonObject& r) { r.Object("pose").Numbers("t", 3); }, "field 'pose.t': item 1"},
      {[](const JsonObject& r) { r.Objects("frames")[0].String("file"); },
       "field 'frames[0].file'"},
      {[](const JsonObject& r) { r.IntegersOr("list"); },
       "field 'list': expected a list of integers"},
      {[](const JsonObject& r) { r.Object("view").String("x"); },
       "field 'view': expected an object, got -1"},
  };
  for (const auto& [read, expected] : cases) {
    const JsonObject r(j, "c/journal.jsonl: line 7");
    read(r);
    EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
    EXPECT_EQ(r.status().message().rfind("c/journal.jsonl: line 7: ", 0), 0u)
        << r.status().message();
    EXPECT_NE(r.status().message().find(expected), std::string::npos) << r.status().message();
  }
}

TEST(JsonObject, TheFirstErrorIsKeptAndNotAnObjectIsOne) {
  const json list = json::array({1, 2});
  const JsonObject r(list, "m.json");
  EXPECT_EQ(r.String("a"), "");
  EXPECT_EQ(r.Integer("b"), 0);
  EXPECT_EQ(r.status().message(), "m.json: expected an object, got a list");
}

TEST(ParseJson, RefusesBadSyntaxAndDeepNesting) {
  EXPECT_TRUE(ParseJson(R"({"a": [1, 2]})", "x").ok());
  EXPECT_EQ(ParseJson("{\"a\": ", "x.json").status().message(), "x.json: not valid JSON");
  const std::string deep = std::string(10000, '[') + std::string(10000, ']');
  EXPECT_EQ(ParseJson(deep, "deep.json").status().code(), StatusCode::kCorruptData);
  EXPECT_FALSE(ParseJson("[1e400]", "x").ok());
  EXPECT_FALSE(ParseJson("[NaN]", "x").ok());
}

}  // namespace
}  // namespace hairrig
