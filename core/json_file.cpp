#include "core/json_file.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/file_util.h"

namespace hairrig {

namespace {

const nlohmann::json& NullJson() {
  static const nlohmann::json null;
  return null;
}

std::string JoinPath(const std::string& parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  if (key.empty()) return parent;
  return parent + "." + std::string(key);
}

// "a string", "-1", "\"abc\"" (cut at 40 characters): what a field held.
std::string Shown(const nlohmann::json& v) {
  if (v.is_null()) return "nothing";
  if (v.is_array()) return "a list";
  if (v.is_object()) return "an object";
  std::string text = v.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

std::string RangeText(double min, double max) {
  const auto number = [](double v) {
    std::string t = std::to_string(v);
    t.erase(t.find_last_not_of('0') + 1);
    if (!t.empty() && t.back() == '.') t.pop_back();
    return t;
  };
  if (std::isfinite(min) && std::isfinite(max))
    return " in [" + number(min) + ", " + number(max) + "]";
  if (std::isfinite(min)) return " >= " + number(min);
  if (std::isfinite(max)) return " <= " + number(max);
  return "";
}

std::string IntRangeText(const JsonIntRange& r) {
  const JsonIntRange all;
  if (r.min != all.min && r.max != all.max)
    return " in [" + std::to_string(r.min) + ", " + std::to_string(r.max) + "]";
  if (r.min != all.min) return " >= " + std::to_string(r.min);
  if (r.max != all.max) return " <= " + std::to_string(r.max);
  return "";
}

// The value as an int64 in range, or false.
bool ToInteger(const nlohmann::json& v, const JsonIntRange& range, int64_t* out) {
  if (v.is_number_unsigned()) {
    const uint64_t u = v.get<uint64_t>();
    if (u > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return false;
    *out = static_cast<int64_t>(u);
  } else if (v.is_number_integer()) {
    *out = v.get<int64_t>();
  } else {
    return false;
  }
  return *out >= range.min && *out <= range.max;
}

bool ToNumber(const nlohmann::json& v, const JsonRange& range, double* out) {
  if (!v.is_number()) return false;
  *out = v.get<double>();
  return std::isfinite(*out) && *out >= range.min && *out <= range.max;
}

}  // namespace

Result<nlohmann::json> ParseJson(std::string_view text, const std::string& where) {
  int deepest = 0;
  const nlohmann::json::parser_callback_t depth = [&deepest](int d, nlohmann::json::parse_event_t,
                                                             nlohmann::json&) {
    deepest = std::max(deepest, d);
    return true;
  };
  nlohmann::json j =
      nlohmann::json::parse(text.begin(), text.end(), depth, /*allow_exceptions=*/false);
  if (j.is_discarded()) return CorruptData(where + ": not valid JSON");
  if (deepest > kMaxJsonDepth)
    return CorruptData(where + ": not valid JSON (nested deeper than " +
                       std::to_string(kMaxJsonDepth) + " levels)");
  return j;
}

Result<nlohmann::json> ReadJsonFile(const std::string& path, const std::string& hint) {
  Result<std::string> text = ReadFileText(path, kMaxJsonFileBytes);
  if (!text.ok() && text.status().code() == StatusCode::kNotFound && !hint.empty())
    return NotFound(text.status().message() + "; " + hint);
  if (!text.ok()) return text.status();
  return ParseJson(*text, path);
}

JsonObject::JsonObject(const nlohmann::json& j, std::string where)
    : JsonObject(&j, std::move(where), "", std::make_shared<Status>()) {}

JsonObject::JsonObject(const nlohmann::json* j, std::string where, std::string path,
                       std::shared_ptr<Status> error)
    : j_(j), where_(std::move(where)), path_(std::move(path)), error_(std::move(error)) {
  if (!j_->is_object()) Fail("", "expected an object, got " + Shown(*j_));
}

std::string JsonObject::Describe(std::string_view key) const {
  const std::string field = JoinPath(path_, key);
  return field.empty() ? where_ : where_ + ": field '" + field + "'";
}

void JsonObject::Fail(std::string_view key, const std::string& what) const {
  if (error_->ok()) *error_ = CorruptData(Describe(key) + ": " + what);
}

void JsonObject::Record(const Status& status) const {
  if (error_->ok() && !status.ok()) *error_ = CorruptData(status.message());
}

bool JsonObject::Has(std::string_view key) const {
  if (!j_->is_object()) return false;
  const auto it = j_->find(key);
  return it != j_->end() && !it->is_null();
}

const nlohmann::json& JsonObject::Raw(std::string_view key) const {
  if (!Has(key)) return NullJson();
  return *j_->find(key);
}

const nlohmann::json* JsonObject::Required(std::string_view key) const {
  if (!j_->is_object()) return nullptr;  // already recorded
  if (!Has(key)) {
    Fail(key, "is missing");
    return nullptr;
  }
  return &*j_->find(key);
}

std::string JsonObject::String(std::string_view key) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return "";
  if (!v->is_string()) {
    Fail(key, "expected a string, got " + Shown(*v));
    return "";
  }
  return v->get<std::string>();
}

std::string JsonObject::StringOr(std::string_view key, const std::string& fallback) const {
  return Has(key) ? String(key) : fallback;
}

int64_t JsonObject::Integer(std::string_view key, JsonIntRange range) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return 0;
  int64_t out = 0;
  if (!ToInteger(*v, range, &out)) {
    Fail(key, "expected an integer" + IntRangeText(range) + ", got " + Shown(*v));
    return 0;
  }
  return out;
}

int64_t JsonObject::IntegerOr(std::string_view key, int64_t fallback, JsonIntRange range) const {
  return Has(key) ? Integer(key, range) : fallback;
}

double JsonObject::Number(std::string_view key, JsonRange range) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return 0;
  double out = 0;
  if (!ToNumber(*v, range, &out)) {
    Fail(key, "expected a finite number" + RangeText(range.min, range.max) + ", got " + Shown(*v));
    return 0;
  }
  return out;
}

double JsonObject::NumberOr(std::string_view key, double fallback, JsonRange range) const {
  return Has(key) ? Number(key, range) : fallback;
}

bool JsonObject::Bool(std::string_view key) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return false;
  if (!v->is_boolean()) {
    Fail(key, "expected true or false, got " + Shown(*v));
    return false;
  }
  return v->get<bool>();
}

bool JsonObject::BoolOr(std::string_view key, bool fallback) const {
  return Has(key) ? Bool(key) : fallback;
}

std::vector<double> JsonObject::Numbers(std::string_view key, size_t size) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return {};
  std::vector<double> out(size);
  if (!v->is_array() || v->size() != size) {
    Fail(key, "expected " + std::to_string(size) + " numbers, got " + Shown(*v));
    return {};
  }
  for (size_t i = 0; i < size; ++i) {
    if (!ToNumber((*v)[i], {}, &out[i])) {
      Fail(key, "item " + std::to_string(i) + ": expected a finite number, got " + Shown((*v)[i]));
      return {};
    }
  }
  return out;
}

std::vector<int64_t> JsonObject::IntegersOr(std::string_view key, JsonIntRange range) const {
  if (!Has(key)) return {};
  const nlohmann::json& v = *j_->find(key);
  if (!v.is_array()) {
    Fail(key, "expected a list of integers, got " + Shown(v));
    return {};
  }
  std::vector<int64_t> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    if (!ToInteger(v[i], range, &out[i])) {
      Fail(key, "item " + std::to_string(i) + ": expected an integer" + IntRangeText(range) +
                    ", got " + Shown(v[i]));
      return {};
    }
  }
  return out;
}

JsonObject JsonObject::Object(std::string_view key) const {
  const nlohmann::json* v = Required(key);
  return JsonObject(v == nullptr ? &NullJson() : v, where_, JoinPath(path_, key), error_);
}

std::vector<JsonObject> JsonObject::Objects(std::string_view key) const {
  const nlohmann::json* v = Required(key);
  if (v == nullptr) return {};
  if (!v->is_array()) {
    Fail(key, "expected a list, got " + Shown(*v));
    return {};
  }
  std::vector<JsonObject> out;
  out.reserve(v->size());
  for (size_t i = 0; i < v->size(); ++i)
    out.push_back(
        JsonObject(&(*v)[i], where_, JoinPath(path_, key) + "[" + std::to_string(i) + "]", error_));
  return out;
}

std::vector<std::string> JsonObject::Keys() const {
  std::vector<std::string> keys;
  if (!j_->is_object()) return keys;
  for (auto it = j_->begin(); it != j_->end(); ++it) keys.push_back(it.key());
  return keys;
}

}  // namespace hairrig
