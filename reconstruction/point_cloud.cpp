#include "reconstruction/point_cloud.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

#include "core/file_util.h"
#include "core/ply.h"

namespace hairrig {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the writer stores floats as binary_little_endian");

// The vertex properties the reader knows; kFloatCount of them are floats.
enum Role { kX, kY, kZ, kNx, kNy, kNz, kConfidence, kFloatCount, kViews = kFloatCount, kOther };
constexpr std::array<const char*, kFloatCount + 1> kRoleNames = {"x",  "y",  "z",          "nx",
                                                                 "ny", "nz", "confidence", "views"};

Role RoleOf(const std::string& name) {
  for (size_t r = 0; r < kRoleNames.size(); ++r) {
    if (name == kRoleNames[r]) return static_cast<Role>(r);
  }
  return kOther;
}

class BytePutter {
 public:
  explicit BytePutter(uint8_t* out) : out_(out) {}
  template <typename T>
  void Put(T v) {
    std::memcpy(out_, &v, sizeof(T));
    out_ += sizeof(T);
  }

 private:
  uint8_t* out_;
};

// Reads the items of one list property: its length is checked against the bytes left before
// anything is kept.
Status ReadList(PlyValueReader& reader, const PlyHeader& header, const PlyProperty& p,
                const std::string& name, size_t record, std::vector<uint16_t>* views) {
  double length = 0;
  if (!reader.Next(p.count_type, &length) || !(length >= 0) || length != std::floor(length)) {
    return PlyCorrupt(
        name, "bad list length of property '" + p.name + "' in record " + std::to_string(record));
  }
  const size_t min_item = header.encoding == PlyEncoding::kAscii ? 2 : PlyTypeSize(p.type);
  if (length > static_cast<double>((reader.remaining() + 1) / min_item)) {
    return PlyCorrupt(name, "list '" + p.name + "' of record " + std::to_string(record) +
                                " is longer than the file");
  }
  const auto n = static_cast<size_t>(length);
  if (views) views->reserve(n);
  for (size_t k = 0; k < n; ++k) {
    double value = 0;
    if (!reader.Next(p.type, &value)) {
      return PlyCorrupt(name, "ends or is unreadable inside list '" + p.name + "' of record " +
                                  std::to_string(record));
    }
    if (!views) continue;
    if (!(value >= 0 && value <= 65535) || value != std::floor(value)) {
      return CorruptData(name + ": vertex " + std::to_string(record) + " lists view " +
                         std::to_string(value) + ", not an integer in 0..65535");
    }
    views->push_back(static_cast<uint16_t>(value));
  }
  return Status::Ok();
}

Result<std::vector<OrientedPoint>> DecodePointCloudPly(const std::vector<uint8_t>& bytes,
                                                       const std::string& name) {
  HR_ASSIGN_OR_RETURN(PlyHeader header, ParsePlyHeader(bytes, name));
  PlyValueReader reader(bytes, header);
  std::vector<OrientedPoint> points;
  bool have_vertices = false;
  for (const PlyElement& e : header.elements) {
    const bool is_vertex = e.name == "vertex" && !have_vertices;
    std::vector<Role> roles(e.properties.size(), kOther);
    if (is_vertex) {
      std::array<bool, kFloatCount + 1> found{};
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        roles[i] = RoleOf(p.name);
        if (roles[i] == kOther) continue;
        if (found[roles[i]])
          return PlyCorrupt(name, "the vertex element has property '" + p.name + "' twice");
        if (p.is_list != (roles[i] == kViews)) {
          return PlyCorrupt(
              name, "vertex property '" + p.name + (p.is_list ? "' is a list" : "' is not a list"));
        }
        found[roles[i]] = true;
      }
      for (int r = kX; r <= kNz; ++r) {
        if (!found[r]) {
          return CorruptData(name + ": the vertex element has no property '" + kRoleNames[r] +
                             "' (an oriented point cloud needs x y z nx ny nz)");
        }
      }
    }
    // ParsePlyHeader bounded e.count by the file's size.
    if (is_vertex) {
      have_vertices = true;
      points.resize(e.count);
    }
    for (size_t r = 0; r < e.count; ++r) {
      std::array<float, kFloatCount> values{};
      values[kConfidence] = 1;
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (p.is_list) {
          HR_RETURN_IF_ERROR(ReadList(reader, header, p, name, r,
                                      roles[i] == kViews ? &points[r].views : nullptr));
          continue;
        }
        double value = 0;
        float as_float = 0;
        if (!reader.Next(p.type, &value, &as_float)) {
          return PlyCorrupt(name, "ends or is unreadable at element '" + e.name + "' record " +
                                      std::to_string(r) + " property '" + p.name + "'");
        }
        if (roles[i] >= kFloatCount) continue;
        if (!std::isfinite(as_float)) {
          return CorruptData(name + ": vertex " + std::to_string(r) + " has a non-finite " +
                             p.name + " (" + std::to_string(value) + ")");
        }
        values[roles[i]] = as_float;
      }
      if (!is_vertex) continue;
      OrientedPoint& point = points[r];
      point.position_mm = Eigen::Vector3f(values[kX], values[kY], values[kZ]);
      point.direction = Eigen::Vector3f(values[kNx], values[kNy], values[kNz]);
      point.confidence = values[kConfidence];
    }
    if (is_vertex) break;  // nothing after the vertices is needed
  }
  if (!have_vertices) return PlyCorrupt(name, "has no 'vertex' element");
  return points;
}

}  // namespace

Status WritePointCloudPly(const std::string& path, const std::vector<OrientedPoint>& points) {
  size_t max_views = 0, total_views = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const OrientedPoint& p = points[i];
    if (!p.position_mm.allFinite() || !p.direction.allFinite() || !std::isfinite(p.confidence)) {
      return InvalidArgument(
          path + ": point " + std::to_string(i) +
          " has a non-finite position, direction or confidence; nothing written");
    }
    if (p.views.size() > 65535) {
      return InvalidArgument(path + ": point " + std::to_string(i) +
                             " lists more than 65535 views; nothing written");
    }
    max_views = std::max(max_views, p.views.size());
    total_views += p.views.size();
  }
  const bool wide_count = max_views > 255;
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\n"
    << "comment written by hairrig: oriented points, mm; normals are unit strand directions "
       "(unsigned)\n"
    << "element vertex " << points.size() << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "property float confidence\n"
    << "property list " << (wide_count ? "ushort" : "uchar") << " ushort views\nend_header\n";
  const std::string text = h.str();
  const size_t count_bytes = wide_count ? 2 : 1;
  std::vector<uint8_t> bytes(text.size() + points.size() * (7 * sizeof(float) + count_bytes) +
                             2 * total_views);
  std::memcpy(bytes.data(), text.data(), text.size());
  BytePutter out(bytes.data() + text.size());
  for (const OrientedPoint& p : points) {
    for (int k = 0; k < 3; ++k) out.Put(p.position_mm[k]);
    for (int k = 0; k < 3; ++k) out.Put(p.direction[k]);
    out.Put(p.confidence);
    if (wide_count) {
      out.Put(static_cast<uint16_t>(p.views.size()));
    } else {
      out.Put(static_cast<uint8_t>(p.views.size()));
    }
    for (uint16_t v : p.views) out.Put(v);
  }
  return WriteFileAtomic(path, bytes.data(), bytes.size());
}

Result<std::vector<OrientedPoint>> ReadPointCloudPly(const std::string& path) {
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(path));
  return DecodePointCloudPly(bytes, path);
}

}  // namespace hairrig
