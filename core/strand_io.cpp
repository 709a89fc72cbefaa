#include "core/strand_io.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>

#include "core/file_util.h"
#include "core/ply.h"

namespace hairrig {
namespace {

// Bounds-checked little-endian reader over a byte buffer.
class ByteReader {
 public:
  ByteReader(const std::vector<uint8_t>& bytes, size_t pos = 0) : bytes_(bytes), pos_(pos) {}
  size_t remaining() const { return bytes_.size() - pos_; }
  size_t pos() const { return pos_; }
  bool Read(void* out, size_t n) {
    if (n > remaining()) return false;
    std::memcpy(out, bytes_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  template <typename T>
  bool Get(T* out) {
    return Read(out, sizeof(T));
  }

 private:
  const std::vector<uint8_t>& bytes_;
  size_t pos_;
};

class ByteWriter {
 public:
  template <typename T>
  void Put(const T& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void PutText(const std::string& s) { bytes.insert(bytes.end(), s.begin(), s.end()); }
  std::vector<uint8_t> bytes;
};

Status Corrupt(const std::string& name, const std::string& what) {
  return CorruptData(name + ": " + what +
                     " (the file is truncated or not in the format its name says)");
}

Status ReadPoints(ByteReader& in, size_t count, const std::string& name, StrandSet* set) {
  if (count > in.remaining() / 12) {
    return Corrupt(name, "needs " + std::to_string(count) + " points but only " +
                             std::to_string(in.remaining()) + " bytes are left");
  }
  const size_t first = set->points_mm.size();
  set->points_mm.resize(first + count);
  for (size_t i = 0; i < count; ++i) {
    float xyz[3];
    in.Read(xyz, sizeof(xyz));
    set->points_mm[first + i] = Eigen::Vector3f(xyz[0], xyz[1], xyz[2]);
  }
  return Status::Ok();
}

// ----- Cem Yuksel .hair ---------------------------------------------------
constexpr uint32_t kHairHasSegments = 1u << 0;
constexpr uint32_t kHairHasPoints = 1u << 1;
constexpr uint32_t kHairHasThickness = 1u << 2;
constexpr uint32_t kHairHasTransparency = 1u << 3;
constexpr uint32_t kHairHasColor = 1u << 4;

struct HairHeader {
  char magic[4];
  uint32_t strand_count;
  uint32_t point_count;
  uint32_t flags;
  uint32_t default_segments;
  float default_thickness;
  float default_transparency;
  float default_color[3];
  char info[88];
};
static_assert(sizeof(HairHeader) == 128, "the .hair header is 128 bytes");

Result<StrandSet> DecodeHair(const std::vector<uint8_t>& bytes, const std::string& name) {
  ByteReader in(bytes);
  HairHeader h;
  if (!in.Get(&h)) return Corrupt(name, "shorter than the 128-byte .hair header");
  if (std::memcmp(h.magic, "HAIR", 4) != 0) return Corrupt(name, "does not start with 'HAIR'");
  if (!(h.flags & kHairHasPoints))
    return Corrupt(name, "header says the file holds no points array");
  // Counts are checked against the bytes that follow before anything is allocated.
  const uint64_t needed = uint64_t{h.point_count} * 12 +
                          ((h.flags & kHairHasSegments) ? uint64_t{h.strand_count} * 2 : 0);
  if (needed > in.remaining()) {
    return Corrupt(name, "header claims " + std::to_string(h.strand_count) + " strands of " +
                             std::to_string(h.point_count) + " points, more than the " +
                             std::to_string(in.remaining()) + " bytes after it hold");
  }
  StrandSet set;
  if (h.flags & kHairHasSegments) {
    set.point_counts.resize(h.strand_count);
    for (auto& c : set.point_counts) {
      uint16_t segments = 0;
      in.Get(&segments);
      c = uint32_t{segments} + 1;
    }
  } else {
    if (h.default_segments > 65535u) return Corrupt(name, "default segment count above 65535");
    if (uint64_t{h.strand_count} * (h.default_segments + 1) != h.point_count) {
      return Corrupt(name, "strand count times default segments does not match the point count");
    }
    set.point_counts.assign(h.strand_count, h.default_segments + 1);
  }
  uint64_t total = 0;
  for (uint32_t c : set.point_counts) total += c;
  if (total != h.point_count) {
    return Corrupt(name, "segment counts add up to " + std::to_string(total) +
                             " points but the header says " + std::to_string(h.point_count));
  }
  HR_RETURN_IF_ERROR(ReadPoints(in, h.point_count, name, &set));
  const size_t per_point_floats = ((h.flags & kHairHasThickness) ? 1 : 0) +
                                  ((h.flags & kHairHasTransparency) ? 1 : 0) +
                                  ((h.flags & kHairHasColor) ? 3 : 0);
  if (per_point_floats * 4 > 0 && in.remaining() / (per_point_floats * 4) < h.point_count) {
    return Corrupt(name, "thickness/transparency/colour arrays are shorter than the point count");
  }
  const size_t skip =
      size_t{h.point_count} * 4 *
      (((h.flags & kHairHasThickness) ? 1 : 0) + ((h.flags & kHairHasTransparency) ? 1 : 0));
  ByteReader colors(bytes, in.pos() + skip);
  if (h.flags & kHairHasColor) {
    set.colors.resize(h.point_count);
    for (auto& c : set.colors) {
      float rgb[3];
      colors.Read(rgb, sizeof(rgb));
      for (int k = 0; k < 3; ++k) {
        const float v = std::isfinite(rgb[k]) ? std::fmin(std::fmax(rgb[k], 0.f), 1.f) : 0.f;
        c[k] = static_cast<uint8_t>(std::lround(v * 255.f));
      }
    }
  }
  return set;
}

Result<std::vector<uint8_t>> EncodeHair(const StrandSet& set) {
  HairHeader h{};
  std::memcpy(h.magic, "HAIR", 4);
  h.strand_count = static_cast<uint32_t>(set.num_strands());
  h.point_count = static_cast<uint32_t>(set.num_points());
  h.flags = kHairHasSegments | kHairHasPoints | (set.colors.empty() ? 0u : kHairHasColor);
  h.default_thickness = 1.f;
  h.default_color[0] = h.default_color[1] = h.default_color[2] = 1.f;
  ByteWriter out;
  out.Put(h);
  for (uint32_t c : set.point_counts) {
    if (c - 1 > 65535u) return InvalidArgument(".hair stores at most 65535 segments per strand");
    out.Put(static_cast<uint16_t>(c - 1));
  }
  for (const auto& p : set.points_mm) out.Put(p);
  for (const auto& c : set.colors) {
    for (int k = 0; k < 3; ++k) out.Put(static_cast<float>(c[k]) / 255.f);
  }
  return std::move(out.bytes);
}

// ----- USC-HairSalon .data --------------------------------------------------
Result<StrandSet> DecodeData(const std::vector<uint8_t>& bytes, const std::string& name) {
  ByteReader in(bytes);
  int32_t strand_count;
  if (!in.Get(&strand_count)) return Corrupt(name, "shorter than the 4-byte strand count");
  if (strand_count < 0 || static_cast<size_t>(strand_count) > in.remaining() / 4) {
    return Corrupt(
        name, "strand count " + std::to_string(strand_count) + " is impossible for the file size");
  }
  StrandSet set;
  set.point_counts.reserve(static_cast<size_t>(strand_count));
  for (int32_t s = 0; s < strand_count; ++s) {
    int32_t count;
    if (!in.Get(&count))
      return Corrupt(name, "ends before the point count of strand " + std::to_string(s));
    if (count < 1)
      return Corrupt(name,
                     "strand " + std::to_string(s) + " has point count " + std::to_string(count));
    HR_RETURN_IF_ERROR(
        ReadPoints(in, static_cast<size_t>(count), name + " strand " + std::to_string(s), &set));
    set.point_counts.push_back(static_cast<uint32_t>(count));
  }
  if (in.remaining() != 0)
    return Corrupt(name,
                   std::to_string(in.remaining()) + " unexpected bytes after the last strand");
  return set;
}

Result<std::vector<uint8_t>> EncodeData(const StrandSet& set) {
  ByteWriter out;
  out.Put(static_cast<int32_t>(set.num_strands()));
  size_t p = 0;
  for (uint32_t c : set.point_counts) {
    out.Put(static_cast<int32_t>(c));
    for (uint32_t k = 0; k < c; ++k) out.Put(set.points_mm[p++]);
  }
  return std::move(out.bytes);
}

// ----- PLY (core/ply.h reads the header and values) -------------------
// Edges are redundant with the strand counts; where present each must join two
// consecutive points of one strand (this catches a file cut inside its last edge).
Status CheckPlyEdges(const StrandSet& set, const std::vector<std::array<double, 2>>& edges,
                     const std::string& name) {
  if (edges.empty()) return Status::Ok();
  std::vector<uint32_t> strand_of(set.num_points(), 0);
  size_t p = 0;
  for (size_t s = 0; s < set.point_counts.size() && p < strand_of.size(); ++s) {
    for (uint32_t k = 0; k < set.point_counts[s] && p < strand_of.size(); ++k)
      strand_of[p++] = static_cast<uint32_t>(s);
  }
  for (size_t i = 0; i < edges.size(); ++i) {
    const double a = edges[i][0], b = edges[i][1];
    const bool valid = a >= 0 && b == a + 1 && b < static_cast<double>(set.num_points()) &&
                       strand_of[static_cast<size_t>(a)] == strand_of[static_cast<size_t>(b)];
    if (!valid)
      return Corrupt(
          name, "edge " + std::to_string(i) + " does not join two consecutive points of a strand");
  }
  return Status::Ok();
}

Result<StrandSet> DecodePly(const std::vector<uint8_t>& bytes, const std::string& name) {
  HR_ASSIGN_OR_RETURN(PlyHeader header, ParsePlyHeader(bytes, name));
  PlyValueReader reader(bytes, header);
  StrandSet set;
  bool have_vertices = false, have_strands = false;
  std::vector<std::array<double, 2>> edges;
  for (const PlyElement& e : header.elements) {
    const bool is_vertex = e.name == "vertex";
    const bool is_strand = e.name == "strand";
    const bool is_edge = e.name == "edge" && e.properties.size() == 2 && !e.properties[0].is_list &&
                         !e.properties[1].is_list;
    if (is_edge) edges.resize(e.count);
    int xyz_index[3] = {-1, -1, -1}, rgb_index[3] = {-1, -1, -1};
    for (size_t i = 0; i < e.properties.size(); ++i) {
      const std::string& n = e.properties[i].name;
      for (int k = 0; k < 3; ++k) {
        if (n == std::array<const char*, 3>{"x", "y", "z"}[k]) xyz_index[k] = static_cast<int>(i);
        if (n == std::array<const char*, 3>{"red", "green", "blue"}[k])
          rgb_index[k] = static_cast<int>(i);
      }
    }
    if (is_vertex) {
      if (xyz_index[0] < 0 || xyz_index[1] < 0 || xyz_index[2] < 0)
        return Corrupt(name, "vertex element lacks x, y or z");
      have_vertices = true;
      set.points_mm.resize(e.count);
      if (rgb_index[0] >= 0 && rgb_index[1] >= 0 && rgb_index[2] >= 0) set.colors.resize(e.count);
    }
    if (is_strand) {
      if (e.properties.size() != 1 || e.properties[0].is_list) {
        return Corrupt(name, "strand element must have exactly one integer property (nsegs)");
      }
      have_strands = true;
      set.point_counts.resize(e.count);
    }
    for (size_t r = 0; r < e.count; ++r) {
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        double value = 0.0;
        float as_float = 0.f;
        if (p.is_list) {
          if (!reader.Next(p.count_type, &value) || value < 0 || value > 1e6) {
            return Corrupt(
                name, "bad list length in element '" + e.name + "' record " + std::to_string(r));
          }
          for (size_t k = 0, n = static_cast<size_t>(value); k < n; ++k) {
            if (!reader.Next(p.type, &value))
              return Corrupt(name, "ends inside element '" + e.name + "'");
          }
          continue;
        }
        if (!reader.Next(p.type, &value, &as_float)) {
          return Corrupt(name, "ends or is unreadable at element '" + e.name + "' record " +
                                   std::to_string(r) + " property '" + p.name + "'");
        }
        const int idx = static_cast<int>(i);
        if (is_vertex) {
          for (int k = 0; k < 3; ++k) {
            if (idx == xyz_index[k]) set.points_mm[r][k] = as_float;
            if (idx == rgb_index[k] && !set.colors.empty()) {
              set.colors[r][k] = static_cast<uint8_t>(std::fmin(std::fmax(value, 0.0), 255.0));
            }
          }
        } else if (is_strand) {
          if (!(value >= 0) || value != std::floor(value) || value > 4e9) {
            return Corrupt(name, "strand " + std::to_string(r) + " has an invalid segment count");
          }
          set.point_counts[r] = static_cast<uint32_t>(value) + 1;
        } else if (is_edge) {
          edges[r][i] = value;
        }
      }
    }
  }
  if (!have_vertices) return Corrupt(name, "has no 'vertex' element");
  if (!have_strands)
    return Corrupt(name, "has no 'strand' element (per-strand 'nsegs'); not a strand PLY");
  HR_RETURN_IF_ERROR(CheckPlyEdges(set, edges, name));
  return set;
}

Result<std::vector<uint8_t>> EncodePly(const StrandSet& set, bool ascii) {
  size_t edges = 0;
  uint32_t max_segments = 0;
  for (uint32_t c : set.point_counts) {
    edges += c - 1;
    max_segments = std::max(max_segments, c - 1);
  }
  const bool has_color = !set.colors.empty();
  const char* nsegs_type = max_segments > 65535u ? "uint" : "ushort";
  std::ostringstream h;
  h << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\n"
    << "comment written by hairrig; units mm\n"
    << "element vertex " << set.num_points()
    << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (has_color) h << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  h << "element strand " << set.num_strands() << "\nproperty " << nsegs_type << " nsegs\n"
    << "element edge " << edges << "\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  ByteWriter out;
  out.PutText(h.str());
  char buf[160];
  for (size_t i = 0; i < set.num_points(); ++i) {
    const auto& p = set.points_mm[i];
    if (ascii) {
      int n = std::snprintf(buf, sizeof(buf), "%.9g %.9g %.9g", static_cast<double>(p.x()),
                            static_cast<double>(p.y()), static_cast<double>(p.z()));
      if (has_color) {
        n += std::snprintf(buf + n, sizeof(buf) - static_cast<size_t>(n), " %d %d %d",
                           set.colors[i][0], set.colors[i][1], set.colors[i][2]);
      }
      out.PutText(std::string(buf, static_cast<size_t>(n)) + "\n");
    } else {
      out.Put(p);
      if (has_color) out.Put(set.colors[i]);
    }
  }
  for (uint32_t c : set.point_counts) {
    if (ascii) {
      out.PutText(std::to_string(c - 1) + "\n");
    } else if (max_segments > 65535u) {
      out.Put(static_cast<uint32_t>(c - 1));
    } else {
      out.Put(static_cast<uint16_t>(c - 1));
    }
  }
  size_t first = 0;
  for (uint32_t c : set.point_counts) {
    for (uint32_t k = 1; k < c; ++k) {
      const auto a = static_cast<int32_t>(first + k - 1), b = static_cast<int32_t>(first + k);
      if (ascii) {
        out.PutText(std::to_string(a) + " " + std::to_string(b) + "\n");
      } else {
        out.Put(a);
        out.Put(b);
      }
    }
    first += c;
  }
  return std::move(out.bytes);
}

}  // namespace

const char* StrandFormatName(StrandFormat format) {
  switch (format) {
    case StrandFormat::kHair:
      return "hair";
    case StrandFormat::kData:
      return "data";
    case StrandFormat::kPlyBinary:
      return "ply (binary)";
    case StrandFormat::kPlyAscii:
      return "ply (ascii)";
  }
  return "?";
}

Result<StrandFormat> StrandFormatFromPath(const std::string& path) {
  const std::string ext = FileExtension(path);
  if (ext == "hair") return StrandFormat::kHair;
  if (ext == "data") return StrandFormat::kData;
  if (ext == "ply") return StrandFormat::kPlyBinary;
  return InvalidArgument(path + ": unknown strand file extension '" + ext +
                         "' (use .hair, .data or .ply)");
}

Result<StrandSet> DecodeStrands(const std::vector<uint8_t>& bytes, StrandFormat format,
                                const std::string& name) {
  Result<StrandSet> set = [&]() -> Result<StrandSet> {
    switch (format) {
      case StrandFormat::kHair:
        return DecodeHair(bytes, name);
      case StrandFormat::kData:
        return DecodeData(bytes, name);
      case StrandFormat::kPlyBinary:
      case StrandFormat::kPlyAscii:
        return DecodePly(bytes, name);
    }
    return Internal("unknown strand format");
  }();
  if (!set.ok()) return set;
  HR_RETURN_IF_ERROR(set->Check().WithContext(name));
  return set;
}

Result<std::vector<uint8_t>> EncodeStrands(const StrandSet& strands, StrandFormat format) {
  HR_RETURN_IF_ERROR(strands.Check().WithContext("cannot write strands"));
  switch (format) {
    case StrandFormat::kHair:
      return EncodeHair(strands);
    case StrandFormat::kData:
      return EncodeData(strands);
    case StrandFormat::kPlyBinary:
      return EncodePly(strands, false);
    case StrandFormat::kPlyAscii:
      return EncodePly(strands, true);
  }
  return Internal("unknown strand format");
}

Result<StrandSet> ReadStrands(const std::string& path) {
  HR_ASSIGN_OR_RETURN(StrandFormat format, StrandFormatFromPath(path));
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(path));
  return DecodeStrands(bytes, format, path);
}

Status WriteStrands(const std::string& path, const StrandSet& strands) {
  HR_ASSIGN_OR_RETURN(StrandFormat format, StrandFormatFromPath(path));
  return WriteStrands(path, strands, format);
}

Status WriteStrands(const std::string& path, const StrandSet& strands, StrandFormat format) {
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, EncodeStrands(strands, format));
  return WriteFileAtomic(path, bytes.data(), bytes.size());
}

}  // namespace hairrig
