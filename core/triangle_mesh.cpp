#include "core/triangle_mesh.h"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "core/file_util.h"
#include "core/ply.h"

namespace hairrig {

Eigen::Vector3d TriangleMesh::FaceNormal(size_t t) const {
  const Eigen::Vector3d n = (Corner(t, 1) - Corner(t, 0)).cross(Corner(t, 2) - Corner(t, 0));
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

double TriangleMesh::FaceArea(size_t t) const {
  return 0.5 * (Corner(t, 1) - Corner(t, 0)).cross(Corner(t, 2) - Corner(t, 0)).norm();
}

Eigen::Vector3d TriangleMesh::MinCorner() const {
  Eigen::Vector3d m = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& v : vertices_mm) m = m.cwiseMin(v);
  return m;
}

Eigen::Vector3d TriangleMesh::MaxCorner() const {
  Eigen::Vector3d m = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  for (const auto& v : vertices_mm) m = m.cwiseMax(v);
  return m;
}

void TriangleMesh::Transform(const Rigid3d& to_from_mesh) {
  for (auto& v : vertices_mm) v = to_from_mesh * v;
}

Status TriangleMesh::Check(const std::string& name) const {
  if (triangles.empty()) return CorruptData(name + ": the mesh has no triangles");
  for (size_t i = 0; i < vertices_mm.size(); ++i) {
    if (!vertices_mm[i].allFinite())
      return CorruptData(name + ": vertex " + std::to_string(i) + " is not finite");
  }
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (uint32_t index : triangles[t]) {
      if (index >= vertices_mm.size()) {
        return CorruptData(name + ": face " + std::to_string(t) + " names vertex " +
                           std::to_string(index) + " of " + std::to_string(vertices_mm.size()));
      }
    }
  }
  return Status::Ok();
}

namespace {

// Fans a polygon (as listed) into triangles; false if an index is not a whole,
// non-negative number.
bool AddPolygon(const std::vector<double>& indices, TriangleMesh* mesh) {
  for (double i : indices) {
    if (!(i >= 0) || i != std::floor(i) || i > 4e9) return false;
  }
  for (size_t k = 2; k < indices.size(); ++k) {
    mesh->triangles.push_back({static_cast<uint32_t>(indices[0]),
                               static_cast<uint32_t>(indices[k - 1]),
                               static_cast<uint32_t>(indices[k])});
  }
  return true;
}

}  // namespace

Result<TriangleMesh> DecodePlyMesh(const std::vector<uint8_t>& bytes, const std::string& name) {
  HR_ASSIGN_OR_RETURN(PlyHeader header, ParsePlyHeader(bytes, name));
  PlyValueReader reader(bytes, header);
  TriangleMesh mesh;
  std::vector<double> polygon;
  for (const PlyElement& e : header.elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    for (size_t i = 0; i < e.properties.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        if (e.properties[i].name == std::string(1, "xyz"[k]) && !e.properties[i].is_list)
          xyz[k] = static_cast<int>(i);
      }
    }
    if (is_vertex) {
      if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)
        return PlyCorrupt(name, "vertex element lacks x, y or z");
      mesh.vertices_mm.resize(e.count);
    }
    if (is_face) mesh.triangles.reserve(e.count);
    for (size_t r = 0; r < e.count; ++r) {
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        double value = 0;
        if (!p.is_list) {
          if (!reader.Next(p.type, &value)) {
            return PlyCorrupt(name, "ends or is unreadable at element '" + e.name + "' record " +
                                        std::to_string(r));
          }
          for (int k = 0; k < 3; ++k) {
            if (is_vertex && static_cast<int>(i) == xyz[k]) mesh.vertices_mm[r][k] = value;
          }
          continue;
        }
        if (!reader.Next(p.count_type, &value) || !(value >= 0) || value > 1e4) {
          return PlyCorrupt(
              name, "bad list length in element '" + e.name + "' record " + std::to_string(r));
        }
        polygon.resize(static_cast<size_t>(value));
        for (double& index : polygon) {
          if (!reader.Next(p.type, &index))
            return PlyCorrupt(name, "ends inside element '" + e.name + "'");
        }
        const bool face_list = is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
        if (face_list && !AddPolygon(polygon, &mesh)) {
          return PlyCorrupt(name, "face " + std::to_string(r) + " has an invalid vertex index");
        }
      }
    }
  }
  HR_RETURN_IF_ERROR(mesh.Check(name));
  return mesh;
}

Result<TriangleMesh> DecodeObjMesh(const std::string& text, const std::string& name) {
  TriangleMesh mesh;
  std::istringstream lines(text);
  std::string line;
  std::vector<double> polygon;
  for (int line_no = 1; std::getline(lines, line); ++line_no) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    const std::string where = name + ":" + std::to_string(line_no);
    if (keyword == "v") {
      Eigen::Vector3d v;
      if (!(words >> v.x() >> v.y() >> v.z()))
        return CorruptData(where + ": a vertex needs three numbers");
      mesh.vertices_mm.push_back(v);
    } else if (keyword == "f") {
      polygon.clear();
      std::string corner;
      while (words >> corner) {
        // "i", "i/t", "i//n" or "i/t/n"; negative indices count back from the last vertex.
        char* end = nullptr;
        const long index = std::strtol(corner.c_str(), &end, 10);
        if (end == corner.c_str() || index == 0)
          return CorruptData(where + ": bad face corner '" + corner + "'");
        const long absolute =
            index > 0 ? index - 1 : static_cast<long>(mesh.vertices_mm.size()) + index;
        polygon.push_back(static_cast<double>(absolute));
      }
      if (polygon.size() < 3 || !AddPolygon(polygon, &mesh)) {
        return CorruptData(where + ": a face needs three or more valid vertex indices");
      }
    }
  }
  HR_RETURN_IF_ERROR(mesh.Check(name));
  return mesh;
}

Result<TriangleMesh> ReadTriangleMesh(const std::string& path) {
  const std::string ext = FileExtension(path);
  if (ext != "ply" && ext != "obj")
    return InvalidArgument(path + ": a mesh file must end in .ply or .obj");
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(path));
  if (ext == "ply") return DecodePlyMesh(bytes, path);
  return DecodeObjMesh(std::string(bytes.begin(), bytes.end()), path);
}

TriangleMesh MakeEllipsoidMesh(const Eigen::Vector3d& center_mm, const Eigen::Vector3d& radii_mm,
                               int rings, int segments) {
  TriangleMesh mesh;
  for (int r = 0; r <= rings; ++r) {
    const double polar = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double azimuth = 2 * kPi * s / segments;
      const Eigen::Vector3d unit(std::sin(polar) * std::cos(azimuth),
                                 std::sin(polar) * std::sin(azimuth), std::cos(polar));
      mesh.vertices_mm.push_back(center_mm + unit.cwiseProduct(radii_mm));
    }
  }
  const auto at = [&](int r, int s) {
    return static_cast<uint32_t>(r * segments + (s % segments));
  };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      // From the north pole (+z) down: (r, s), (r+1, s), (r+1, s+1) winds outward.
      if (r > 0) mesh.triangles.push_back({at(r, s), at(r + 1, s), at(r, s + 1)});
      if (r + 1 < rings) mesh.triangles.push_back({at(r, s + 1), at(r + 1, s), at(r + 1, s + 1)});
    }
  }
  return mesh;
}

}  // namespace hairrig
