#include "core/config.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "core/file_util.h"

namespace hairrig {

struct DocumentErrors {
  std::string file;
  Status first_error;
};

struct ConfigNode::Impl {
  YAML::Node node;
  std::string path;
  std::shared_ptr<DocumentErrors> doc;
};

namespace {

std::string JoinPath(const std::string& parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  return parent + "." + std::string(key);
}

std::string MarkText(const std::string& file, const YAML::Mark& mark) {
  if (mark.line < 0) return file;
  return file + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// A scalar as an error message shows it: quoted when short, single-line text;
// otherwise only its length, so that a message never repeats the content of a
// file named by mistake (a whole /etc/passwd reads as one long scalar).
std::string DescribeScalar(const std::string& text) {
  constexpr size_t kMaxQuotedBytes = 40;
  const bool plain = std::none_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 0x20 || u == 0x7F;
  });
  if (plain && text.size() <= kMaxQuotedBytes) return QuotedExcerpt(text);
  return "text of " + std::to_string(text.size()) + " bytes";
}

std::string Describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return DescribeScalar(node.Scalar());
  if (node.IsSequence()) return "a list";
  return "a map";
}

// Whether `text` is well-formed UTF-8 (RFC 3629: no overlong forms, no
// surrogates, nothing above U+10FFFF).
bool IsValidUtf8(std::string_view text) {
  size_t i = 0;
  while (i < text.size()) {
    const auto lead = static_cast<unsigned char>(text[i]);
    size_t length = 1;
    unsigned char low = 0x80, high = 0xBF;  // the allowed range of the second byte
    if (lead < 0x80) {
      ++i;
      continue;
    } else if (lead >= 0xC2 && lead <= 0xDF) {
      length = 2;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
      length = 3;
      if (lead == 0xE0) low = 0xA0;
      if (lead == 0xED) high = 0x9F;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
      length = 4;
      if (lead == 0xF0) low = 0x90;
      if (lead == 0xF4) high = 0x8F;
    } else {
      return false;
    }
    if (text.size() - i < length) return false;
    for (size_t k = 1; k < length; ++k) {
      const auto c = static_cast<unsigned char>(text[i + k]);
      if (c < (k == 1 ? low : 0x80) || c > (k == 1 ? high : 0xBF)) return false;
    }
    i += length;
  }
  return true;
}

// Walks a document's parse events before any node is built, throwing a
// DocumentProblem at the first of: a second document, a key that is not text
// or that its map already has, text that is not valid UTF-8 (it could not be
// written to JSON), more than kMaxConfigValues values or kMaxConfigDepth levels.
class DocumentChecker : public YAML::EventHandler {
 public:
  struct DocumentProblem {
    YAML::Mark mark;
    std::string what;
  };

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1)
      throw DocumentProblem{mark, "a second YAML document (after '---'); a config file holds one"};
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Value(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Value(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& text) override {
    Value(mark, &text);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Open(mark, /*map=*/false);
  }
  void OnSequenceEnd() override { open_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Open(mark, /*map=*/true);
  }
  void OnMapEnd() override { open_.pop_back(); }

 private:
  struct Collection {
    bool map = false;
    bool at_key = true;               // maps: the next value is a key
    std::map<std::string, int> keys;  // key -> its line (1-based)
    std::string current;              // the key (map) or "[index]" (list) of the latest value
    int items = 0;                    // lists: values so far
  };

  // The dotted path of the latest value, as ConfigNode names fields; without
  // the innermost collection's part when `parent_only`.
  std::string FieldPath(bool parent_only) const {
    std::string path;
    const size_t n = open_.size() - (parent_only && !open_.empty() ? 1 : 0);
    for (size_t i = 0; i < n; ++i) {
      const std::string& part = open_[i].current;
      path += path.empty() || part.rfind('[', 0) == 0 ? part : "." + part;
    }
    return path.empty() ? "'<top>'" : QuotedExcerpt(path);
  }

  // A value inside the innermost open collection; `text` is null for anything but a scalar.
  void Value(const YAML::Mark& mark, const std::string* text) {
    if (++values_ > kMaxConfigValues) {
      throw DocumentProblem{mark, "more than " + std::to_string(kMaxConfigValues) +
                                      " values; is this a config file?"};
    }
    const bool is_key = !open_.empty() && open_.back().map && open_.back().at_key;
    if (!open_.empty() && !open_.back().map)
      open_.back().current = "[" + std::to_string(open_.back().items++) + "]";
    if (text != nullptr && !IsValidUtf8(*text)) {
      throw DocumentProblem{mark, (is_key ? "a key in " : "field ") + FieldPath(is_key) +
                                      ": text that is not valid UTF-8; save the file as UTF-8"};
    }
    if (open_.empty() || !open_.back().map) return;
    Collection& map = open_.back();
    map.at_key = !map.at_key;
    if (map.at_key) return;  // that was the value of a key
    if (text == nullptr) throw DocumentProblem{mark, "a map key must be text"};
    map.current = *text;
    const auto [first, inserted] = map.keys.emplace(*text, mark.line + 1);
    if (!inserted) {
      throw DocumentProblem{mark, "duplicate key " + QuotedExcerpt(*text) + " (first at line " +
                                      std::to_string(first->second) + "); give each key once"};
    }
  }

  void Open(const YAML::Mark& mark, bool map) {
    Value(mark, nullptr);
    if (static_cast<int>(open_.size()) >= kMaxConfigDepth) {
      throw DocumentProblem{mark,
                            "nested deeper than " + std::to_string(kMaxConfigDepth) + " levels"};
    }
    open_.push_back({map, true, {}, {}, 0});
  }

  int documents_ = 0;
  int values_ = 0;
  std::vector<Collection> open_;
};

// Checks `text` with a DocumentChecker; YAML syntax errors propagate as YAML::Exception.
Status CheckDocument(const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentChecker checker;
  try {
    while (parser.HandleNextDocument(checker)) {
    }
  } catch (const DocumentChecker::DocumentProblem& p) {
    return InvalidArgument(MarkText(origin, p.mark) + ": " + p.what);
  }
  return Status::Ok();
}

}  // namespace

std::string QuotedExcerpt(std::string_view text) {
  constexpr size_t kMaxBytes = 60;
  size_t n = std::min(text.size(), kMaxBytes);
  // Whole UTF-8 characters: back off from a continuation byte.
  while (n < text.size() && n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;
  std::string out = "'";
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c == 0x7F ? '?' : text[i];
  }
  if (n == text.size()) return out + "'";
  return out + "...' (" + std::to_string(text.size()) + " bytes)";
}

ConfigNode::ConfigNode() : impl_(std::make_shared<Impl>()) {
  impl_->doc = std::make_shared<DocumentErrors>();
}
ConfigNode::~ConfigNode() = default;
ConfigNode::ConfigNode(const ConfigNode&) = default;
ConfigNode& ConfigNode::operator=(const ConfigNode&) = default;

Result<ConfigNode> ConfigNode::LoadString(const std::string& text, const std::string& origin) {
  if (text.size() > kMaxConfigBytes) {
    return InvalidArgument(origin + ": " + std::to_string(text.size()) +
                           " bytes, more than a config's " + std::to_string(kMaxConfigBytes));
  }
  ConfigNode root;
  root.impl_->doc->file = origin;
  try {
    HR_RETURN_IF_ERROR(CheckDocument(text, origin));
    root.impl_->node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return InvalidArgument(MarkText(origin, e.mark) + ": not valid YAML: " + e.msg);
  }
  if (!root.impl_->node.IsMap()) {
    return InvalidArgument(origin + ": expected a YAML map at the top level, got " +
                           Describe(root.impl_->node));
  }
  return root;
}

Result<ConfigNode> ConfigNode::LoadFile(const std::string& path) {
  Result<std::string> text = ReadFileText(path, kMaxConfigBytes);
  if (!text.ok() && text.status().code() == StatusCode::kNotFound)
    return NotFound(path + ": cannot open the config file (check the path)");
  if (!text.ok()) return text.status();
  return LoadString(*text, path);
}

bool ConfigNode::ok() const { return impl_->doc->first_error.ok(); }
Status ConfigNode::status() const { return impl_->doc->first_error; }
const std::string& ConfigNode::file() const { return impl_->doc->file; }
const std::string& ConfigNode::path() const { return impl_->path; }
std::string ConfigNode::Where() const { return MarkText(file(), impl_->node.Mark()); }
bool ConfigNode::IsMap() const { return impl_->node.IsMap(); }

bool ConfigNode::Has(std::string_view key) const {
  return impl_->node.IsMap() && impl_->node[std::string(key)].IsDefined() &&
         !impl_->node[std::string(key)].IsNull();
}

bool ConfigNode::HasScalar(std::string_view key) const {
  return Has(key) && impl_->node[std::string(key)].IsScalar();
}

void ConfigNode::Fail(std::string_view key, const std::string& what) const {
  if (!ok()) return;
  YAML::Mark mark = impl_->node.Mark();
  if (!key.empty() && Has(key)) mark = impl_->node[std::string(key)].Mark();
  const std::string field = key.empty() ? impl_->path : JoinPath(impl_->path, key);
  const std::string quoted = field.empty() ? "'<top>'" : QuotedExcerpt(field);
  impl_->doc->first_error =
      InvalidArgument(MarkText(file(), mark) + ": field " + quoted + ": " + what);
}

namespace {
// Parses a scalar as a finite double; yaml-cpp accepts ".nan"/".inf" which we refuse.
bool ScalarToDouble(const YAML::Node& node, double* out) {
  if (!node.IsScalar()) return false;
  try {
    *out = node.as<double>();
  } catch (const YAML::Exception&) {
    return false;
  }
  return true;
}

std::string RangeText(NumberRange r) {
  std::ostringstream s;
  if (std::isfinite(r.min) && std::isfinite(r.max)) {
    s << " in [" << r.min << ", " << r.max << "]";
  } else if (std::isfinite(r.min)) {
    s << " >= " << r.min;
  } else if (std::isfinite(r.max)) {
    s << " <= " << r.max;
  }
  return s.str();
}
}  // namespace

double ConfigNode::Number(std::string_view key, NumberRange range) const {
  if (!Has(key)) {
    Fail(key, "required number" + RangeText(range) + " is missing");
    return 0.0;
  }
  const YAML::Node n = impl_->node[std::string(key)];
  double value = 0.0;
  if (!ScalarToDouble(n, &value)) {
    Fail(key, "expected a number" + RangeText(range) + ", got " + Describe(n));
    return 0.0;
  }
  if (!std::isfinite(value)) {
    Fail(key, "expected a finite number, got " + Describe(n));
    return 0.0;
  }
  if (value < range.min || value > range.max) {
    Fail(key, "expected a number" + RangeText(range) + ", got " + Describe(n));
    return 0.0;
  }
  return value;
}

double ConfigNode::Number(std::string_view key, double fallback, NumberRange range) const {
  return Has(key) ? Number(key, range) : fallback;
}

int ConfigNode::Integer(std::string_view key, NumberRange range) const {
  const double v = Number(key, range);
  if (v != std::floor(v) || std::abs(v) > 2e9) {
    Fail(key, "expected a whole number, got " + Describe(impl_->node[std::string(key)]));
    return 0;
  }
  return static_cast<int>(v);
}

int ConfigNode::Integer(std::string_view key, int fallback, NumberRange range) const {
  return Has(key) ? Integer(key, range) : fallback;
}

std::string ConfigNode::String(std::string_view key) const {
  if (!Has(key)) {
    Fail(key, "required text is missing");
    return "";
  }
  const YAML::Node n = impl_->node[std::string(key)];
  if (!n.IsScalar()) {
    Fail(key, "expected text, got " + Describe(n));
    return "";
  }
  return n.Scalar();
}

std::string ConfigNode::String(std::string_view key, const std::string& fallback) const {
  return Has(key) ? String(key) : fallback;
}

std::string ConfigNode::Choice(std::string_view key, std::initializer_list<const char*> choices,
                               const std::string& fallback) const {
  std::string listed;
  for (const char* c : choices) listed += (listed.empty() ? "" : ", ") + std::string(c);
  if (!Has(key) && !fallback.empty()) return fallback;
  const std::string value = String(key);
  if (!ok()) return fallback;
  for (const char* c : choices) {
    if (value == c) return value;
  }
  Fail(key, DescribeScalar(value) + " is not one of: " + listed);
  return fallback;
}

bool ConfigNode::Bool(std::string_view key, bool fallback) const {
  if (!Has(key)) return fallback;
  const YAML::Node n = impl_->node[std::string(key)];
  try {
    if (n.IsScalar()) return n.as<bool>();
  } catch (const YAML::Exception&) {
  }
  Fail(key, "expected true or false, got " + Describe(n));
  return fallback;
}

std::vector<double> ConfigNode::Numbers(std::string_view key, size_t expected_size,
                                        NumberRange range) const {
  if (!Has(key)) {
    Fail(key, "required list of numbers is missing");
    return {};
  }
  const YAML::Node n = impl_->node[std::string(key)];
  if (!n.IsSequence()) {
    Fail(key, "expected a list of numbers, got " + Describe(n));
    return {};
  }
  std::vector<double> values;
  for (size_t i = 0; i < n.size(); ++i) {
    double v = 0.0;
    if (!ScalarToDouble(n[i], &v) || !std::isfinite(v)) {
      Fail(key, "element " + std::to_string(i) + " is not a finite number: " + Describe(n[i]));
      return {};
    }
    if (v < range.min || v > range.max) {
      Fail(key, "element " + std::to_string(i) + ": expected a number" + RangeText(range) +
                    ", got " + Describe(n[i]));
      return {};
    }
    values.push_back(v);
  }
  if (expected_size != 0 && values.size() != expected_size) {
    Fail(key, "expected " + std::to_string(expected_size) + " numbers, got " +
                  std::to_string(values.size()));
    return {};
  }
  return values;
}

std::vector<std::string> ConfigNode::Strings(std::string_view key) const {
  const YAML::Node n = Has(key) ? impl_->node[std::string(key)] : YAML::Node();
  if (!n.IsSequence()) {
    Fail(key, Has(key) ? "expected a list of names, got " + Describe(n)
                       : "required list of names is missing");
    return {};
  }
  std::vector<std::string> values;
  for (size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar()) {
      Fail(key, "element " + std::to_string(i) + " is not text: " + Describe(n[i]));
      return {};
    }
    values.push_back(n[i].Scalar());
  }
  return values;
}

Eigen::Vector3d ConfigNode::Vec3(std::string_view key, NumberRange range) const {
  const auto v = Numbers(key, 3, range);
  if (v.size() != 3) return Eigen::Vector3d::Zero();
  return {v[0], v[1], v[2]};
}

Eigen::Vector3d ConfigNode::Vec3(std::string_view key, const Eigen::Vector3d& fallback,
                                 NumberRange range) const {
  return Has(key) ? Vec3(key, range) : fallback;
}

ConfigNode ConfigNode::OptionalChild(std::string_view key) const {
  ConfigNode child;
  child.impl_->doc = impl_->doc;
  child.impl_->path = JoinPath(impl_->path, key);
  if (Has(key)) {
    child.impl_->node = impl_->node[std::string(key)];
    if (!child.impl_->node.IsMap()) Fail(key, "expected a map, got " + Describe(child.impl_->node));
  }
  return child;
}

ConfigNode ConfigNode::Child(std::string_view key) const {
  if (!Has(key)) Fail(key, "required section is missing");
  return OptionalChild(key);
}

std::vector<ConfigNode> ConfigNode::OptionalItems(std::string_view key) const {
  std::vector<ConfigNode> items;
  if (!Has(key)) return items;
  const YAML::Node n = impl_->node[std::string(key)];
  if (!n.IsSequence()) {
    Fail(key, "expected a list, got " + Describe(n));
    return items;
  }
  for (size_t i = 0; i < n.size(); ++i) {
    ConfigNode item;
    item.impl_->doc = impl_->doc;
    item.impl_->path = JoinPath(impl_->path, key) + "[" + std::to_string(i) + "]";
    item.impl_->node = n[i];
    if (!n[i].IsMap()) {
      item.Fail("", "expected a map, got " + Describe(n[i]));
      continue;
    }
    items.push_back(item);
  }
  return items;
}

std::vector<ConfigNode> ConfigNode::Items(std::string_view key) const {
  if (!Has(key)) Fail(key, "required list is missing");
  return OptionalItems(key);
}

std::vector<std::string> ConfigNode::Keys() const {
  std::vector<std::string> keys;
  if (!impl_->node.IsMap()) return keys;
  for (const auto& kv : impl_->node) keys.push_back(kv.first.Scalar());
  return keys;
}

void ConfigNode::AllowOnlyKeys(std::initializer_list<const char*> allowed) const {
  AllowOnlyKeys(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void ConfigNode::AllowOnlyKeys(const std::vector<std::string>& allowed) const {
  if (!impl_->node.IsMap()) return;
  for (const auto& kv : impl_->node) {
    const std::string key = kv.first.Scalar();
    bool known = false;
    std::string listed;
    for (const std::string& a : allowed) {
      known = known || key == a;
      listed += (listed.empty() ? "" : ", ") + a;
    }
    if (!known) {
      if (!ok()) return;
      impl_->doc->first_error = InvalidArgument(
          MarkText(file(), kv.first.Mark()) + ": unknown field " +
          QuotedExcerpt(JoinPath(impl_->path, key)) + " (expected one of: " + listed + ")");
      return;
    }
  }
}

}  // namespace hairrig
