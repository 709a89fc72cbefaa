#include "core/config.h"

#include <cmath>
#include <sstream>

#include <yaml-cpp/yaml.h>

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

std::string Describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  return "a map";
}

}  // namespace

ConfigNode::ConfigNode() : impl_(std::make_shared<Impl>()) {
  impl_->doc = std::make_shared<DocumentErrors>();
}
ConfigNode::~ConfigNode() = default;
ConfigNode::ConfigNode(const ConfigNode&) = default;
ConfigNode& ConfigNode::operator=(const ConfigNode&) = default;

Result<ConfigNode> ConfigNode::LoadString(const std::string& text, const std::string& origin) {
  ConfigNode root;
  root.impl_->doc->file = origin;
  try {
    root.impl_->node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return InvalidArgument(MarkText(origin, e.mark) + ": not valid YAML: " + e.msg);
  }
  if (!root.impl_->node.IsMap()) {
    return InvalidArgument(origin + ": expected a YAML map at the top level, got " + Describe(root.impl_->node));
  }
  return root;
}

Result<ConfigNode> ConfigNode::LoadFile(const std::string& path) {
  Result<std::string> text = ReadFileText(path, kMaxConfigFileBytes);
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
  impl_->doc->first_error =
      InvalidArgument(MarkText(file(), mark) + ": field '" + (field.empty() ? "<top>" : field) + "': " + what);
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
  Fail(key, "'" + value + "' is not one of: " + listed);
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

std::vector<double> ConfigNode::Numbers(std::string_view key, size_t expected_size) const {
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
    values.push_back(v);
  }
  if (expected_size != 0 && values.size() != expected_size) {
    Fail(key, "expected " + std::to_string(expected_size) + " numbers, got " + std::to_string(values.size()));
    return {};
  }
  return values;
}

std::vector<std::string> ConfigNode::Strings(std::string_view key) const {
  const YAML::Node n = Has(key) ? impl_->node[std::string(key)] : YAML::Node();
  if (!n.IsSequence()) {
    Fail(key, Has(key) ? "expected a list of names, got " + Describe(n) : "required list of names is missing");
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

Eigen::Vector3d ConfigNode::Vec3(std::string_view key) const {
  const auto v = Numbers(key, 3);
  if (v.size() != 3) return Eigen::Vector3d::Zero();
  return {v[0], v[1], v[2]};
}

Eigen::Vector3d ConfigNode::Vec3(std::string_view key, const Eigen::Vector3d& fallback) const {
  return Has(key) ? Vec3(key) : fallback;
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
  if (!impl_->node.IsMap()) return;
  for (const auto& kv : impl_->node) {
    const std::string key = kv.first.Scalar();
    bool known = false;
    std::string listed;
    for (const char* a : allowed) {
      known = known || key == a;
      listed += (listed.empty() ? "" : ", ") + std::string(a);
    }
    if (!known) {
      if (!ok()) return;
      impl_->doc->first_error = InvalidArgument(MarkText(file(), kv.first.Mark()) + ": unknown field '" +
                                                JoinPath(impl_->path, key) + "' (expected one of: " + listed + ")");
      return;
    }
  }
}

}  // namespace hairrig
