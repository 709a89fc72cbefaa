// PLY files (ascii and binary, either byte order): the header's elements and
// properties, and a bounds-checked reader of the values that follow it. Shared
// by the strand reader (core/strand_io.h) and the mesh reader
// (core/triangle_mesh.h). Errors are CorruptData naming the file and the header
// line; a value reader never reads past the end of the bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

// False for a type name PLY does not define.
bool ParsePlyType(const std::string& t, PlyType* out);
size_t PlyTypeSize(PlyType t);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
  size_t MinRecordBytes() const {
    size_t n = 0;
    for (const auto& p : properties) n += PlyTypeSize(p.is_list ? p.count_type : p.type);
    return n;
  }
};

enum class PlyEncoding { kAscii, kBinaryLittle, kBinaryBig };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;
};

// The header of `bytes` (`name` is for messages). Element counts are checked
// against the bytes after the header (each record takes at least its fixed
// bytes, or two characters per value in ascii) and an element with records but
// no properties is refused, so a reader may size its arrays from the counts.
Result<PlyHeader> ParsePlyHeader(const std::vector<uint8_t>& bytes, const std::string& name);

// CorruptData: "<name>: <what> (the file is truncated or not in the format its name says)".
Status PlyCorrupt(const std::string& name, const std::string& what);

// Reads the values of one PLY body in order, ascii or binary, with bounds checks.
class PlyValueReader {
 public:
  PlyValueReader(const std::vector<uint8_t>& bytes, const PlyHeader& h)
      : bytes_(bytes), pos_(h.data_offset), encoding_(h.encoding) {}
  size_t remaining() const { return bytes_.size() - pos_; }

  // Reads one value as double (and as float exactly when `as_float` is given).
  // False at the end of the bytes or on an unreadable ascii token.
  bool Next(PlyType type, double* value, float* as_float = nullptr);

 private:
  bool NextAscii(PlyType type, double* value, float* as_float);

  const std::vector<uint8_t>& bytes_;
  size_t pos_;
  PlyEncoding encoding_;
};

}  // namespace hairrig
