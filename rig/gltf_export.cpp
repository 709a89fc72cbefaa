#include "rig/gltf_export.h"

#include <algorithm>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/head_config.h"
#include "core/head_model.h"
#include "core/json_file.h"
#include "core/strand_io.h"
#include "core/string_format.h"
#include "rig/capture_calibration_input.h"

namespace hairrig {

namespace {

namespace fs = std::filesystem;

constexpr const char* kStrandsFile = "/reconstruction/strands/strands.ply";

// The head spec and where it came from, or no head (empty source).
Result<std::pair<std::optional<HeadSpec>, std::string>> FindHead(const GltfExportOptions& o) {
  if (!o.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(const HeadSpec head, LoadHeadFile(o.head_file));
    return std::make_pair(std::optional<HeadSpec>(head), o.head_file);
  }
  const std::string fitted = o.dir + "/reconstruction/head.yaml";
  std::error_code ec;
  if (fs::is_regular_file(fitted, ec)) {
    HR_ASSIGN_OR_RETURN(const HeadSpec head, LoadHeadFile(fitted));
    return std::make_pair(std::optional<HeadSpec>(head), fitted);
  }
  if (fs::is_regular_file(o.dir + "/rig.yaml", ec)) {
    HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(o.dir));
    if (config.head) return std::make_pair(config.head, o.dir + "/rig.yaml");
  }
  return std::make_pair(std::optional<HeadSpec>(), std::string());
}

// A simulation folder's frames (frames/frame_NNNN.*, in order) and its fps.
struct SimulationFrames {
  std::vector<StrandSet> frames;
  double fps = 30;
};

// Each frame decimated as it is read (a frame of 20,000 strands is about 60 MB).
Result<SimulationFrames> ReadSimulation(const std::string& dir, int max_strands, int max_points) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/frames", ec))
    if (e.is_regular_file(ec) && e.path().filename().string().rfind("frame_", 0) == 0)
      files.push_back(e.path().string());
  if (ec || files.empty())
    return NotFound(dir + "/frames: no frame_NNNN strand files (a `hairrig simulate` output)");
  std::sort(files.begin(), files.end());
  SimulationFrames out;
  if (Result<nlohmann::json> summary = ReadJsonFile(dir + "/summary.json"); summary.ok()) {
    const JsonObject s(*summary, dir + "/summary.json");
    out.fps = s.NumberOr("fps", 30, {.min = 1e-3, .max = 1e4});
    HR_RETURN_IF_ERROR(s.status());
  }
  for (const std::string& file : files) {
    HR_ASSIGN_OR_RETURN(const StrandSet frame, ReadStrands(file));
    out.frames.push_back(DecimateStrands(frame, max_strands, max_points));
  }
  return out;
}

std::string DisplayPath(const std::string& out_file) {
  const fs::path path(out_file);
  return (path.parent_path() / (path.stem().string() + ".display.glb")).string();
}

// The scene of one level: `strands`, the head, the frames.
GltfScene SceneOf(const StrandSet& strands, const TriangleMesh* head,
                  const std::vector<StrandSet>& frames, const std::string& animation, double fps) {
  GltfScene scene;
  scene.strand_sets.push_back({.name = "strands", .strands = &strands});
  if (head != nullptr) scene.meshes.push_back({.name = "head", .mesh = head});
  if (!frames.empty()) {
    GltfStrandAnimation a{.name = animation, .frames = {}, .fps = fps};
    for (const StrandSet& f : frames) a.frames.push_back(&f);
    scene.animations.push_back(std::move(a));
  }
  return scene;
}

}  // namespace

Status GltfExportOptions::Check() const {
  if (dir.empty()) return InvalidArgument("export: the capture folder is required");
  if (display_strands < 1 || display_strands > 1000000)
    return InvalidArgument("export: --display-strands must be in 1 .. 1,000,000");
  if (display_points < 2 || display_points > 10000)
    return InvalidArgument("export: --display-points must be in 2 .. 10,000");
  return Status::Ok();
}

StrandSet DecimateStrands(const StrandSet& strands, int max_strands, int max_points) {
  const size_t n = strands.point_counts.size();
  const size_t stride = std::max<size_t>(
      1, (n + static_cast<size_t>(max_strands) - 1) / static_cast<size_t>(max_strands));
  StrandSet out;
  size_t first = 0;
  for (size_t s = 0; s < n; ++s) {
    const uint32_t count = strands.point_counts[s];
    if (s % stride == 0 && count > 0) {
      const uint32_t step = std::max<uint32_t>(1, (count + static_cast<uint32_t>(max_points) - 2) /
                                                      static_cast<uint32_t>(max_points - 1));
      uint32_t kept = 0;
      for (uint32_t i = 0; i < count; i += step, ++kept) {
        out.points_mm.push_back(strands.points_mm[first + i]);
        if (!strands.colors.empty()) out.colors.push_back(strands.colors[first + i]);
      }
      if ((count - 1) % step != 0) {  // the tip
        out.points_mm.push_back(strands.points_mm[first + count - 1]);
        if (!strands.colors.empty()) out.colors.push_back(strands.colors[first + count - 1]);
        ++kept;
      }
      out.point_counts.push_back(kept);
    }
    first += count;
  }
  return out;
}

nlohmann::json GltfExportSummary::ToJson() const {
  auto level = [](const GltfWriteSummary& s) {
    return nlohmann::json{{"path", s.path},         {"bytes", s.bytes},
                          {"strands", s.strands},   {"vertices", s.vertices},
                          {"segments", s.segments}, {"frames", s.frames}};
  };
  return {{"full", level(full)}, {"display", level(display)}, {"head", head_source}};
}

std::string GltfExportSummary::BriefReport() const {
  std::string text;
  for (const GltfWriteSummary* s : {&full, &display}) {
    if (s->path.empty()) continue;
    text += StringPrintf("%s: %lld strands, %lld vertices, %d animation frames, %.1f MB\n",
                         s->path.c_str(), static_cast<long long>(s->strands),
                         static_cast<long long>(s->vertices), s->frames,
                         static_cast<double>(s->bytes) / 1e6);
  }
  text += head_source.empty() ? "  no head (give --head FILE)\n" : "  head: " + head_source + "\n";
  return text;
}

Result<GltfExportSummary> ExportCaptureGltf(const GltfExportOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  const std::string out_file =
      o.out_file.empty() ? o.dir + "/reconstruction/strands/hair.glb" : o.out_file;
  HR_ASSIGN_OR_RETURN(const StrandSet strands, ReadStrands(o.dir + kStrandsFile));
  HR_ASSIGN_OR_RETURN(const auto head, FindHead(o));
  GltfExportSummary summary;
  summary.head_source = head.second;
  std::unique_ptr<HeadModel> head_model;
  if (head.first) {
    HR_ASSIGN_OR_RETURN(head_model, HeadModel::Build(*head.first));
  }
  const TriangleMesh* head_mesh = head_model ? &head_model->mesh() : nullptr;

  SimulationFrames simulation;
  std::string animation;
  if (!o.simulation_dir.empty()) {
    HR_ASSIGN_OR_RETURN(simulation,
                        ReadSimulation(o.simulation_dir, o.display_strands, o.display_points));
    animation = fs::path(o.simulation_dir).filename().string();
    if (animation.empty()) animation = "simulation";
  }
  if (!o.display_only) {
    HR_ASSIGN_OR_RETURN(summary.full,
                        WriteGlb(out_file, SceneOf(strands, head_mesh, simulation.frames, animation,
                                                   simulation.fps)));
  }
  const StrandSet display = DecimateStrands(strands, o.display_strands, o.display_points);
  HR_ASSIGN_OR_RETURN(summary.display,
                      WriteGlb(DisplayPath(out_file), SceneOf(display, head_mesh, simulation.frames,
                                                              animation, simulation.fps)));
  return summary;
}

}  // namespace hairrig
