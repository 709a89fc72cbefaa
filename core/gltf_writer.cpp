#include "core/gltf_writer.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/file_util.h"

namespace hairrig {

namespace {

// glTF 2.0 constants (specification sections 3.6 and 4.4 of the GLB container).
constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kJsonChunk = 0x4E4F534A;
constexpr uint32_t kBinChunk = 0x004E4942;
constexpr int kUnsignedByte = 5121, kUnsignedInt = 5125, kFloat = 5126;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kPointsMode = 0, kLinesMode = 1, kTrianglesMode = 4;
constexpr int64_t kMaxStrands = int64_t{1} << 24;  // the strand id is an exact float below this

// mm, +z up -> m, +y up (a rotation of -90 deg about x).
Eigen::Vector3f ToGltf(const Eigen::Vector3f& p_mm) {
  return Eigen::Vector3f(p_mm.x(), p_mm.z(), -p_mm.y()) * 1e-3f;
}

nlohmann::json Vec3Json(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

// The JSON document and the binary chunk being built.
class GlbBuilder {
 public:
  nlohmann::json doc = {{"asset", {{"version", "2.0"}}},
                        {"scene", 0},
                        {"scenes", {{{"nodes", nlohmann::json::array()}}}},
                        {"nodes", nlohmann::json::array()},
                        {"meshes", nlohmann::json::array()},
                        {"materials", nlohmann::json::array()},
                        {"accessors", nlohmann::json::array()},
                        {"bufferViews", nlohmann::json::array()}};
  std::vector<uint8_t> bin;

  // Positions converted to glTF's frame, with the bounds glTF requires.
  int AddPositions(const std::vector<Eigen::Vector3f>& points_mm) {
    std::vector<Eigen::Vector3f> converted;
    converted.reserve(points_mm.size());
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
    for (const Eigen::Vector3f& p : points_mm) {
      converted.push_back(ToGltf(p));
      lo = lo.cwiseMin(converted.back());
      hi = hi.cwiseMax(converted.back());
    }
    return AddVec3(converted, kArrayBuffer, {{"min", Vec3Json(lo)}, {"max", Vec3Json(hi)}});
  }
  int AddVec3(const std::vector<Eigen::Vector3f>& values, int target, nlohmann::json extra = {}) {
    const int view = AddView(values.data(), values.size() * sizeof(Eigen::Vector3f), target);
    return AddAccessor(view, kFloat, values.size(), "VEC3", std::move(extra));
  }
  int AddScalars(const std::vector<float>& values, int target, nlohmann::json extra = {}) {
    const int view = AddView(values.data(), values.size() * sizeof(float), target);
    return AddAccessor(view, kFloat, values.size(), "SCALAR", std::move(extra));
  }
  int AddColours(const std::vector<std::array<uint8_t, 3>>& colours) {
    std::vector<uint8_t> rgba;
    rgba.reserve(colours.size() * 4);
    for (const auto& c : colours) rgba.insert(rgba.end(), {c[0], c[1], c[2], 255});
    const int view = AddView(rgba.data(), rgba.size(), kArrayBuffer);
    return AddAccessor(view, kUnsignedByte, colours.size(), "VEC4", {{"normalized", true}});
  }
  int AddIndices(const std::vector<uint32_t>& indices) {
    const int view =
        AddView(indices.data(), indices.size() * sizeof(uint32_t), kElementArrayBuffer);
    return AddAccessor(view, kUnsignedInt, indices.size(), "SCALAR");
  }
  int AddMaterial(const std::array<float, 4>& colour, bool double_sided) {
    return Append(
        "materials",
        {{"pbrMetallicRoughness",
          {{"baseColorFactor", colour}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.8}}},
         {"doubleSided", double_sided}});
  }
  int AddMeshNode(const std::string& name, nlohmann::json primitive) {
    const int mesh = Append("meshes", {{"name", name}, {"primitives", {std::move(primitive)}}});
    return Append("nodes", {{"name", name}, {"mesh", mesh}});
  }
  int Append(const char* array, nlohmann::json value) {
    if (!doc.contains(array)) doc[array] = nlohmann::json::array();
    doc[array].push_back(std::move(value));
    return static_cast<int>(doc[array].size()) - 1;
  }

 private:
  int AddView(const void* data, size_t bytes, int target) {
    const size_t offset = bin.size();
    bin.resize(offset + bytes);
    if (bytes > 0) std::memcpy(bin.data() + offset, data, bytes);
    bin.resize((bin.size() + 3) / 4 * 4, 0);  // every view starts 4-byte aligned
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    if (target != 0) view["target"] = target;
    return Append("bufferViews", std::move(view));
  }
  int AddAccessor(int view, int component_type, size_t count, const char* type,
                  nlohmann::json extra = {}) {
    nlohmann::json accessor = {
        {"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}};
    if (extra.is_object()) accessor.update(extra);
    return Append("accessors", std::move(accessor));
  }
};

Status CheckStrands(const std::string& name, const StrandSet& strands) {
  const std::string what = "glTF strand set '" + name + "'";
  if (strands.point_counts.empty()) return InvalidArgument(what + " has no strands");
  if (static_cast<int64_t>(strands.point_counts.size()) > kMaxStrands)
    return InvalidArgument(what + " has more than 2^24 strands");
  uint64_t total = 0;
  for (const uint32_t count : strands.point_counts) total += count;
  if (total != strands.points_mm.size())
    return InvalidArgument(what + ": its strands' point counts sum to " + std::to_string(total) +
                           ", not its " + std::to_string(strands.points_mm.size()) + " points");
  if (!strands.colors.empty() && strands.colors.size() != strands.points_mm.size())
    return InvalidArgument(what + ": " + std::to_string(strands.colors.size()) + " colours for " +
                           std::to_string(strands.points_mm.size()) + " points");
  for (size_t i = 0; i < strands.points_mm.size(); ++i)
    if (!strands.points_mm[i].allFinite())
      return InvalidArgument(what + ": point " + std::to_string(i) + " is not finite");
  return Status::Ok();
}

// An index pair per segment of every strand.
std::vector<uint32_t> SegmentIndices(const StrandSet& strands) {
  std::vector<uint32_t> indices;
  uint32_t first = 0;
  for (const uint32_t count : strands.point_counts) {
    for (uint32_t i = 1; i < count; ++i) indices.insert(indices.end(), {first + i - 1, first + i});
    first += count;
  }
  return indices;
}

// Segments of every strand: a strand of n points has n - 1.
int64_t SegmentCount(const StrandSet& strands) {
  int64_t segments = 0;
  for (const uint32_t count : strands.point_counts) segments += count > 0 ? count - 1 : 0;
  return segments;
}

// Per vertex, its strand's index (`per_strand` null) or its strand's value.
std::vector<float> PerStrand(const StrandSet& strands,
                             const std::vector<uint32_t>* per_strand = nullptr) {
  std::vector<float> ids;
  ids.reserve(strands.points_mm.size());
  for (size_t s = 0; s < strands.point_counts.size(); ++s) {
    const size_t value = per_strand != nullptr ? (*per_strand)[s] : s;
    ids.insert(ids.end(), strands.point_counts[s], static_cast<float>(value));
  }
  return ids;
}

Status CheckWisps(const std::string& name, const StrandSet& strands,
                  const std::vector<uint32_t>* wisps) {
  if (wisps == nullptr) return Status::Ok();
  const std::string what = "glTF strand set '" + name + "'";
  if (wisps->size() != strands.point_counts.size())
    return InvalidArgument(what + ": " + std::to_string(wisps->size()) + " wisp ids for " +
                           std::to_string(strands.point_counts.size()) + " strands");
  for (const uint32_t wisp : *wisps)
    if (wisp >= kMaxStrands)
      return InvalidArgument(what + ": wisp id " + std::to_string(wisp) + " is 2^24 or more");
  return Status::Ok();
}

// Accessors an animation's frames share (-1: each node makes its own).
struct SharedAccessors {
  int indices = -1, ids = -1, wisps = -1;
};

// A LINES node for `strands`, with _WISP_ID from `wisps` (or `shared`) when given.
int AddStrandNode(GlbBuilder* b, const std::string& name, const StrandSet& strands, int material,
                  SharedAccessors shared, GltfWriteSummary* summary,
                  const std::vector<uint32_t>* wisps = nullptr) {
  nlohmann::json attributes = {{"POSITION", b->AddPositions(strands.points_mm)}};
  attributes["_STRAND_ID"] =
      shared.ids >= 0 ? shared.ids : b->AddScalars(PerStrand(strands), kArrayBuffer);
  if (shared.wisps >= 0) attributes["_WISP_ID"] = shared.wisps;
  if (shared.wisps < 0 && wisps != nullptr)
    attributes["_WISP_ID"] = b->AddScalars(PerStrand(strands, wisps), kArrayBuffer);
  if (!strands.colors.empty()) attributes["COLOR_0"] = b->AddColours(strands.colors);
  summary->vertices += static_cast<int64_t>(strands.points_mm.size());
  return b->AddMeshNode(
      name,
      {{"attributes", attributes},
       {"indices", shared.indices >= 0 ? shared.indices : b->AddIndices(SegmentIndices(strands))},
       {"mode", kLinesMode},
       {"material", material}});
}

// Area-weighted vertex normals, in glTF's frame.
std::vector<Eigen::Vector3f> VertexNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices_mm.size(), Eigen::Vector3d::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices_mm[t[0]];
    const Eigen::Vector3d n = (mesh.vertices_mm[t[1]] - a).cross(mesh.vertices_mm[t[2]] - a);
    for (const uint32_t v : t) sum[v] += n;
  }
  std::vector<Eigen::Vector3f> normals;
  normals.reserve(sum.size());
  for (const Eigen::Vector3d& n : sum) {
    const Eigen::Vector3d unit = n.norm() > 0 ? n.normalized() : Eigen::Vector3d::UnitZ();
    normals.push_back(Eigen::Vector3f(static_cast<float>(unit.x()), static_cast<float>(unit.z()),
                                      static_cast<float>(-unit.y())));
  }
  return normals;
}

Result<int> AddMesh(GlbBuilder* b, const GltfTriangleMesh& m, GltfWriteSummary* summary) {
  const std::string what = "glTF mesh '" + m.name + "'";
  if (m.mesh == nullptr || m.mesh->triangles.empty()) return InvalidArgument(what + " is empty");
  std::vector<Eigen::Vector3f> vertices;
  vertices.reserve(m.mesh->vertices_mm.size());
  for (const Eigen::Vector3d& v : m.mesh->vertices_mm) {
    if (!v.allFinite()) return InvalidArgument(what + " has a vertex that is not finite");
    vertices.push_back(v.cast<float>());
  }
  std::vector<uint32_t> indices;
  indices.reserve(3 * m.mesh->triangles.size());
  for (const auto& t : m.mesh->triangles) {
    for (const uint32_t v : t) {
      if (v >= vertices.size())
        return InvalidArgument(what + ": a triangle indexes vertex " + std::to_string(v) + " of " +
                               std::to_string(vertices.size()));
      indices.push_back(v);
    }
  }
  summary->vertices += static_cast<int64_t>(vertices.size());
  const nlohmann::json attributes = {{"POSITION", b->AddPositions(vertices)},
                                     {"NORMAL", b->AddVec3(VertexNormals(*m.mesh), kArrayBuffer)}};
  return b->AddMeshNode(m.name, {{"attributes", attributes},
                                 {"indices", b->AddIndices(indices)},
                                 {"mode", kTrianglesMode},
                                 {"material", b->AddMaterial(m.colour, false)}});
}

Result<int> AddPointCloud(GlbBuilder* b, const GltfPointCloud& c, GltfWriteSummary* summary) {
  const std::string what = "glTF point cloud '" + c.name + "'";
  if (c.points_mm == nullptr || c.points_mm->empty()) return InvalidArgument(what + " is empty");
  if (c.colours != nullptr && c.colours->size() != c.points_mm->size())
    return InvalidArgument(what + ": " + std::to_string(c.colours->size()) + " colours for " +
                           std::to_string(c.points_mm->size()) + " points");
  for (size_t i = 0; i < c.points_mm->size(); ++i)
    if (!(*c.points_mm)[i].allFinite())
      return InvalidArgument(what + ": point " + std::to_string(i) + " is not finite");
  nlohmann::json attributes = {{"POSITION", b->AddPositions(*c.points_mm)}};
  if (c.colours != nullptr) attributes["COLOR_0"] = b->AddColours(*c.colours);
  summary->vertices += static_cast<int64_t>(c.points_mm->size());
  return b->AddMeshNode(c.name, {{"attributes", attributes},
                                 {"mode", kPointsMode},
                                 {"material", b->AddMaterial(c.colour, true)}});
}

Status CheckAnimation(const GltfStrandAnimation& a) {
  const std::string what = "glTF animation '" + a.name + "'";
  if (a.frames.empty()) return InvalidArgument(what + " has no frames");
  if (!(a.fps > 0 && std::isfinite(a.fps))) return InvalidArgument(what + ": fps must be positive");
  for (size_t f = 0; f < a.frames.size(); ++f) {
    if (a.frames[f] == nullptr)
      return InvalidArgument(what + ": frame " + std::to_string(f) + " is missing");
    HR_RETURN_IF_ERROR(CheckStrands(a.name + "' frame '" + std::to_string(f), *a.frames[f]));
    if (a.frames[f]->point_counts != a.frames[0]->point_counts)
      return InvalidArgument(
          what + ": frame " + std::to_string(f) +
          " has other strands than frame 0 (every frame needs the same point counts)");
  }
  return CheckWisps(a.name, *a.frames[0], a.wisps);
}

// The frames as children of one node, shown in turn by STEP scale channels.
int AddAnimation(GlbBuilder* b, const GltfStrandAnimation& a, GltfWriteSummary* summary) {
  const StrandSet& first = *a.frames[0];
  const int material = b->AddMaterial(a.colour, true);
  SharedAccessors shared{.indices = b->AddIndices(SegmentIndices(first)),
                         .ids = b->AddScalars(PerStrand(first), kArrayBuffer)};
  if (a.wisps != nullptr) shared.wisps = b->AddScalars(PerStrand(first, a.wisps), kArrayBuffer);
  const size_t n = a.frames.size();
  // A key per frame and one at n / fps closing the last frame's interval, so
  // that the animation lasts n / fps and a player looping it shows every frame.
  std::vector<float> times(n + 1);
  for (size_t k = 0; k <= n; ++k) times[k] = static_cast<float>(static_cast<double>(k) / a.fps);
  const int input = b->AddScalars(times, 0, {{"min", {times.front()}}, {"max", {times.back()}}});
  nlohmann::json children = nlohmann::json::array(), samplers = nlohmann::json::array(),
                 channels = nlohmann::json::array();
  for (size_t f = 0; f < n; ++f) {
    const int node = AddStrandNode(b, a.name + "_frame_" + std::to_string(f), *a.frames[f],
                                   material, shared, summary);
    if (f != 0) b->doc["nodes"][node]["scale"] = {0.0, 0.0, 0.0};
    std::vector<Eigen::Vector3f> scales(n + 1, Eigen::Vector3f::Zero());
    scales[f] = Eigen::Vector3f::Ones();
    scales[n] = scales[n - 1];
    samplers.push_back(
        {{"input", input}, {"output", b->AddVec3(scales, 0)}, {"interpolation", "STEP"}});
    channels.push_back({{"sampler", f}, {"target", {{"node", node}, {"path", "scale"}}}});
    children.push_back(node);
  }
  b->Append("animations", {{"name", a.name}, {"samplers", samplers}, {"channels", channels}});
  summary->frames += static_cast<int>(n);
  summary->segments += SegmentCount(first);
  return b->Append("nodes", {{"name", a.name}, {"children", children}});
}

// Frame k's positions minus frame 0's, in glTF's frame, with the bounds glTF
// requires of a morph target's POSITION.
int AddOffsets(GlbBuilder* b, const StrandSet& frame, const StrandSet& first) {
  std::vector<Eigen::Vector3f> offsets;
  offsets.reserve(frame.points_mm.size());
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < frame.points_mm.size(); ++i) {
    offsets.push_back(ToGltf(frame.points_mm[i]) - ToGltf(first.points_mm[i]));
    lo = lo.cwiseMin(offsets.back());
    hi = hi.cwiseMax(offsets.back());
  }
  return b->AddVec3(offsets, kArrayBuffer, {{"min", Vec3Json(lo)}, {"max", Vec3Json(hi)}});
}

// Frame 0 as one node, frame k (k >= 1) as its morph target k - 1, whose
// weight LINEAR keys raise to 1 at k / fps.
int AddMorphAnimation(GlbBuilder* b, const GltfStrandAnimation& a, GltfWriteSummary* summary) {
  const StrandSet& first = *a.frames[0];
  const size_t n = a.frames.size();
  const int node =
      AddStrandNode(b, a.name, first, b->AddMaterial(a.colour, true), {}, summary, a.wisps);
  summary->frames += static_cast<int>(n);
  summary->segments += SegmentCount(first);
  if (n == 1) return node;
  nlohmann::json targets = nlohmann::json::array();
  for (size_t f = 1; f < n; ++f)
    targets.push_back({{"POSITION", AddOffsets(b, *a.frames[f], first)}});
  const int mesh = b->doc["nodes"][node]["mesh"];
  b->doc["meshes"][mesh]["primitives"][0]["targets"] = targets;
  b->doc["meshes"][mesh]["weights"] = std::vector<float>(n - 1, 0.0f);
  std::vector<float> times(n + 1), weights((n + 1) * (n - 1), 0.0f);
  for (size_t k = 0; k <= n; ++k) {
    times[k] = static_cast<float>(static_cast<double>(k) / a.fps);
    const size_t shown = std::min(k, n - 1);  // the closing key holds the last frame
    if (shown > 0) weights[k * (n - 1) + shown - 1] = 1.0f;
  }
  const int input = b->AddScalars(times, 0, {{"min", {times.front()}}, {"max", {times.back()}}});
  b->Append(
      "animations",
      {{"name", a.name},
       {"samplers",
        {{{"input", input}, {"output", b->AddScalars(weights, 0)}, {"interpolation", "LINEAR"}}}},
       {"channels", {{{"sampler", 0}, {"target", {{"node", node}, {"path", "weights"}}}}}}});
  return node;
}

void AppendU32(std::vector<uint8_t>* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

}  // namespace

Result<std::vector<uint8_t>> EncodeGlb(const GltfScene& scene, GltfWriteSummary* summary_out) {
  GltfWriteSummary summary;
  GlbBuilder b;
  b.doc["asset"]["generator"] = scene.generator;
  std::vector<int> roots;
  for (const GltfStrandSet& set : scene.strand_sets) {
    if (set.strands == nullptr)
      return InvalidArgument("glTF strand set '" + set.name + "' is missing");
    HR_RETURN_IF_ERROR(CheckStrands(set.name, *set.strands));
    HR_RETURN_IF_ERROR(CheckWisps(set.name, *set.strands, set.wisps));
    roots.push_back(AddStrandNode(&b, set.name, *set.strands, b.AddMaterial(set.colour, true), {},
                                  &summary, set.wisps));
    summary.strands += static_cast<int64_t>(set.strands->point_counts.size());
    summary.segments += SegmentCount(*set.strands);
  }
  for (const GltfTriangleMesh& mesh : scene.meshes) {
    HR_ASSIGN_OR_RETURN(const int node, AddMesh(&b, mesh, &summary));
    roots.push_back(node);
  }
  for (const GltfPointCloud& cloud : scene.point_clouds) {
    HR_ASSIGN_OR_RETURN(const int node, AddPointCloud(&b, cloud, &summary));
    roots.push_back(node);
  }
  for (const GltfStrandAnimation& animation : scene.animations) {
    HR_RETURN_IF_ERROR(CheckAnimation(animation));
    roots.push_back(animation.encoding == GltfAnimationEncoding::kMorphTargets
                        ? AddMorphAnimation(&b, animation, &summary)
                        : AddAnimation(&b, animation, &summary));
    summary.strands += static_cast<int64_t>(animation.frames[0]->point_counts.size());
  }
  if (roots.empty())
    return InvalidArgument("glTF: nothing to write (no strands, mesh, points or animation)");
  b.doc["scenes"][0]["nodes"] = roots;
  b.doc["buffers"] = {{{"byteLength", b.bin.size()}}};
  for (const char* array : {"meshes", "materials"})
    if (b.doc[array].empty()) b.doc.erase(array);
  summary.nodes = static_cast<int>(b.doc["nodes"].size());

  std::string json = b.doc.dump();
  json.resize((json.size() + 3) / 4 * 4, ' ');
  std::vector<uint8_t> out;
  const size_t total = 12 + 8 + json.size() + 8 + b.bin.size();
  if (total > UINT32_MAX) return InvalidArgument("glTF: the file would exceed 4 GiB (GLB's limit)");
  out.reserve(total);
  AppendU32(&out, kGlbMagic);
  AppendU32(&out, 2);
  AppendU32(&out, static_cast<uint32_t>(total));
  AppendU32(&out, static_cast<uint32_t>(json.size()));
  AppendU32(&out, kJsonChunk);
  out.insert(out.end(), json.begin(), json.end());
  AppendU32(&out, static_cast<uint32_t>(b.bin.size()));
  AppendU32(&out, kBinChunk);
  out.insert(out.end(), b.bin.begin(), b.bin.end());
  summary.bytes = static_cast<int64_t>(out.size());
  if (summary_out != nullptr) *summary_out = summary;
  return out;
}

Result<GltfWriteSummary> WriteGlb(const std::string& path, const GltfScene& scene) {
  GltfWriteSummary summary;
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, EncodeGlb(scene, &summary));
  HR_RETURN_IF_ERROR(WriteFileAtomic(path, bytes.data(), bytes.size()));
  summary.path = path;
  return summary;
}

}  // namespace hairrig
