#include "core/ply.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

namespace hairrig {
namespace {

template <typename T>
T Load(const uint8_t* raw) {
  T v;
  std::memcpy(&v, raw, sizeof(T));
  return v;
}

}  // namespace

Status PlyCorrupt(const std::string& name, const std::string& what) {
  return CorruptData(name + ": " + what +
                     " (the file is truncated or not in the format its name says)");
}

bool ParsePlyType(const std::string& t, PlyType* out) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16},  {"uint16", PlyType::kUInt16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUInt32},     {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, type] : kNames) {
    if (t == n) {
      *out = type;
      return true;
    }
  }
  return false;
}

size_t PlyTypeSize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUInt8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUInt16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUInt32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

namespace {

// Every record takes at least its fixed bytes (binary) or a character and a
// separator per value (ascii; the file's last value may lack its separator), so
// the counts of all elements together are bounded by the body's size.
Status CheckElementCounts(const PlyHeader& header, size_t body_bytes, const std::string& name) {
  const bool ascii = header.encoding == PlyEncoding::kAscii;
  uint64_t left = body_bytes + (ascii ? 1 : 0);
  for (const PlyElement& e : header.elements) {
    if (e.count == 0) continue;
    if (e.properties.empty())
      return PlyCorrupt(name, "element '" + e.name + "' claims " + std::to_string(e.count) +
                                  " records but has no properties");
    const uint64_t per_record = ascii ? 2 * e.properties.size() : e.MinRecordBytes();
    if (e.count > left / per_record) {
      return PlyCorrupt(name, "element '" + e.name + "' claims " + std::to_string(e.count) +
                                  " records, more than the " + std::to_string(body_bytes) +
                                  " bytes after the header hold");
    }
    left -= e.count * per_record;
  }
  return Status::Ok();
}

}  // namespace

Result<PlyHeader> ParsePlyHeader(const std::vector<uint8_t>& bytes, const std::string& name) {
  const std::string end_marker = "end_header";
  const size_t scan = std::min<size_t>(bytes.size(), 1 << 20);
  const std::string head(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(scan));
  if (head.rfind("ply", 0) != 0) return PlyCorrupt(name, "does not start with 'ply'");
  const size_t end = head.find(end_marker);
  if (end == std::string::npos) return PlyCorrupt(name, "has no 'end_header' line");
  size_t data = end + end_marker.size();
  if (data < head.size() && head[data] == '\r') ++data;
  if (data >= head.size() || head[data] != '\n')
    return PlyCorrupt(name, "'end_header' is not followed by a newline");
  PlyHeader header;
  header.data_offset = data + 1;
  std::istringstream lines(head.substr(0, end));
  std::string line;
  bool have_format = false;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    const std::string where = "header line " + std::to_string(line_no);
    if (keyword == "format") {
      std::string enc;
      words >> enc;
      if (enc == "ascii")
        header.encoding = PlyEncoding::kAscii;
      else if (enc == "binary_little_endian")
        header.encoding = PlyEncoding::kBinaryLittle;
      else if (enc == "binary_big_endian")
        header.encoding = PlyEncoding::kBinaryBig;
      else
        return PlyCorrupt(name, where + ": unknown format '" + enc + "'");
      have_format = true;
    } else if (keyword == "element") {
      PlyElement e;
      long long count = -1;
      words >> e.name >> count;
      if (e.name.empty() || count < 0) return PlyCorrupt(name, where + ": malformed element line");
      e.count = static_cast<size_t>(count);
      header.elements.push_back(e);
    } else if (keyword == "property") {
      if (header.elements.empty()) return PlyCorrupt(name, where + ": property before any element");
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!ParsePlyType(count_type, &p.count_type) || !ParsePlyType(item_type, &p.type)) {
          return PlyCorrupt(name, where + ": unknown list types");
        }
      } else {
        words >> p.name;
        if (!ParsePlyType(type, &p.type))
          return PlyCorrupt(name, where + ": unknown property type '" + type + "'");
      }
      if (p.name.empty()) return PlyCorrupt(name, where + ": property without a name");
      header.elements.back().properties.push_back(p);
    } else if (keyword == "ply" || keyword == "comment" || keyword == "obj_info" ||
               keyword.empty()) {
      continue;
    } else {
      return PlyCorrupt(name, where + ": unknown keyword '" + keyword + "'");
    }
  }
  if (!have_format) return PlyCorrupt(name, "header has no 'format' line");
  HR_RETURN_IF_ERROR(CheckElementCounts(header, bytes.size() - header.data_offset, name));
  return header;
}

namespace {

// A double as float, beyond float's range as infinity (a plain cast would be undefined there).
float ToFloat(double v) {
  if (std::abs(v) > static_cast<double>(std::numeric_limits<float>::max()))
    return v > 0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

}  // namespace

bool PlyValueReader::Next(PlyType type, double* value, float* as_float) {
  if (encoding_ == PlyEncoding::kAscii) return NextAscii(type, value, as_float);
  const size_t n = PlyTypeSize(type);
  if (n > remaining()) return false;
  uint8_t raw[8];
  std::memcpy(raw, bytes_.data() + pos_, n);
  pos_ += n;
  if (encoding_ == PlyEncoding::kBinaryBig) std::reverse(raw, raw + n);
  switch (type) {
    case PlyType::kInt8:
      *value = static_cast<int8_t>(raw[0]);
      break;
    case PlyType::kUInt8:
      *value = raw[0];
      break;
    case PlyType::kInt16:
      *value = Load<int16_t>(raw);
      break;
    case PlyType::kUInt16:
      *value = Load<uint16_t>(raw);
      break;
    case PlyType::kInt32:
      *value = Load<int32_t>(raw);
      break;
    case PlyType::kUInt32:
      *value = Load<uint32_t>(raw);
      break;
    case PlyType::kFloat32: {
      const float f = Load<float>(raw);
      if (as_float) *as_float = f;
      *value = f;
      break;
    }
    case PlyType::kFloat64:
      *value = Load<double>(raw);
      break;
  }
  if (as_float && type != PlyType::kFloat32) *as_float = ToFloat(*value);
  return true;
}

bool PlyValueReader::NextAscii(PlyType type, double* value, float* as_float) {
  while (pos_ < bytes_.size() && std::isspace(bytes_[pos_])) ++pos_;
  const size_t start = pos_;
  while (pos_ < bytes_.size() && !std::isspace(bytes_[pos_]) && pos_ - start < 64) ++pos_;
  if (pos_ == start) return false;
  const std::string token(bytes_.begin() + static_cast<std::ptrdiff_t>(start),
                          bytes_.begin() + static_cast<std::ptrdiff_t>(pos_));
  char* end = nullptr;
  if (type == PlyType::kFloat32) {
    const float f = std::strtof(token.c_str(), &end);
    if (as_float) *as_float = f;
    *value = f;
  } else {
    *value = std::strtod(token.c_str(), &end);
    if (as_float) *as_float = ToFloat(*value);
  }
  return end == token.c_str() + token.size();
}

}  // namespace hairrig
