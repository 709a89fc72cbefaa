// Reading JSON documents from files a user can hand in or edit (a capture's
// journal.jsonl, manifest.json and capture.json, calibration.json, intrinsics
// files, helix models, ground truth) with errors that name the file, the
// record and the field, and never an exception.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace hairrig {

// The largest JSON file ReadJsonFile reads: 64 MiB (a journal of about 200,000
// records, a helix model of some 10,000 guides).
inline constexpr uint64_t kMaxJsonFileBytes = uint64_t{64} << 20;
// Deeper nesting is refused: no file of this project nests more than a few levels.
inline constexpr int kMaxJsonDepth = 64;

// `text` as one JSON document. CorruptData "<where>: not valid JSON (...)"
// for bad syntax, a number out of range or nesting deeper than kMaxJsonDepth.
Result<nlohmann::json> ParseJson(std::string_view text, const std::string& where);

// A regular file of at most kMaxJsonFileBytes (core/file_util.h ReadFileChunks),
// parsed by ParseJson. NotFound when the file is absent (the message adds
// `hint`, what to do about it); InvalidArgument for a folder, FIFO or device;
// OutOfRange when it is too large; CorruptData when it is not valid JSON.
Result<nlohmann::json> ReadJsonFile(const std::string& path, const std::string& hint = "");

// Checked reads of one JSON object's fields: the one way the project's
// readers take a field from a JSON file.
//
//   JsonObject record(j, "c/journal.jsonl: line 12");
//   const std::string sha = record.String("sha256");
//   const int64_t view = record.Integer("view", {.min = 0});
//   HR_RETURN_IF_ERROR(record.status());
//     -> "CorruptData: c/journal.jsonl: line 12: field 'view': expected an integer >= 0, got -1"
//
// Accessors never throw. The first problem (a value that is not an object, a
// field missing, of the wrong type, not finite or out of range) is recorded in
// state shared with every JsonObject made from this one (Object, Objects) and
// a neutral value (0, "", false, empty) is returned, so a reader takes all its
// fields and then checks status() once. The ...Or accessors take their fallback
// when the field is absent or null and type-check it when it is present.
// A JsonObject refers to the json it was made from, which must outlive it.
// Inclusive bounds of JsonObject::Integer and JsonObject::Number.
struct JsonIntRange {
  int64_t min = std::numeric_limits<int64_t>::min();
  int64_t max = std::numeric_limits<int64_t>::max();
};
struct JsonRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

class JsonObject {
 public:
  // `where` names the file and the record: "c/journal.jsonl: line 12". The
  // object reads `j` in place: `j` must outlive it (a temporary is refused).
  JsonObject(const nlohmann::json& j, std::string where);
  JsonObject(nlohmann::json&& j, std::string where) = delete;

  bool ok() const { return error_->ok(); }
  Status status() const { return *error_; }
  // "<where>: field '<path>.<key>'", the prefix of this object's messages.
  std::string Describe(std::string_view key) const;
  // Present and not null.
  bool Has(std::string_view key) const;

  std::string String(std::string_view key) const;
  std::string StringOr(std::string_view key, const std::string& fallback) const;
  int64_t Integer(std::string_view key, JsonIntRange range = {}) const;
  int64_t IntegerOr(std::string_view key, int64_t fallback, JsonIntRange range = {}) const;
  // A finite number (JSON integers included).
  double Number(std::string_view key, JsonRange range = {}) const;
  double NumberOr(std::string_view key, double fallback, JsonRange range = {}) const;
  bool Bool(std::string_view key) const;
  bool BoolOr(std::string_view key, bool fallback) const;
  // Exactly `size` finite numbers.
  std::vector<double> Numbers(std::string_view key, size_t size) const;
  // Integers, each in `range`; absent or null: empty.
  std::vector<int64_t> IntegersOr(std::string_view key, JsonIntRange range = {}) const;

  // A required object; after an error, an empty one whose reads fail quietly.
  JsonObject Object(std::string_view key) const;
  // A required array of objects, named "<key>[i]" in messages.
  std::vector<JsonObject> Objects(std::string_view key) const;
  // The keys of this object, sorted.
  std::vector<std::string> Keys() const;
  // The raw value of a field (null when absent), for readers that take a
  // whole sub-document (core/geometry_json.h).
  const nlohmann::json& Raw(std::string_view key) const;

  // Records `what` against field `key` ("" for this object) if nothing was recorded yet.
  void Fail(std::string_view key, const std::string& what) const;
  // Records another reader's error (its message already names the field) as CorruptData.
  void Record(const Status& status) const;

 private:
  JsonObject(const nlohmann::json* j, std::string where, std::string path,
             std::shared_ptr<Status> error);
  // The field's value, or nullptr (with an error recorded) when it is absent or null.
  const nlohmann::json* Required(std::string_view key) const;

  const nlohmann::json* j_;
  std::string where_;
  std::string path_;  // dotted path of this object inside the record: "intrinsics", "frames[3]"
  std::shared_ptr<Status> error_;
};

}  // namespace hairrig
