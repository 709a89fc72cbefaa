#include "rig/gltf_export.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/head_config.h"
#include "core/head_model.h"
#include "core/json_file.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/strand_io.h"
#include "core/string_format.h"
#include "reconstruction/point_cloud.h"
#include "rig/capture_calibration_input.h"

namespace hairrig {

namespace {

namespace fs = std::filesystem;

constexpr const char* kStrandsFile = "/reconstruction/strands/strands.ply";
constexpr const char* kPointsFile = "/reconstruction/points.ply";
constexpr const char* kTruthStrandsFile = "/ground_truth/ground_truth_strands.ply";
constexpr const char* kModelFile = "/simulation/model.json";
constexpr int kMaxGuides = 1000000;
constexpr std::array<float, 4> kGuideColour{0.9f, 0.45f, 0.1f, 1.0f};

bool IsFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

// The head spec and where it came from, or no head (empty source).
Result<std::pair<std::optional<HeadSpec>, std::string>> FindHead(const GltfExportOptions& o) {
  if (!o.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(const HeadSpec head, LoadHeadFile(o.head_file));
    return std::make_pair(std::optional<HeadSpec>(head), o.head_file);
  }
  const std::string fitted = o.dir + "/reconstruction/head.yaml";
  if (IsFile(fitted)) {
    HR_ASSIGN_OR_RETURN(const HeadSpec head, LoadHeadFile(fitted));
    return std::make_pair(std::optional<HeadSpec>(head), fitted);
  }
  if (IsFile(o.dir + "/rig.yaml")) {
    HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(o.dir));
    if (config.head) return std::make_pair(config.head, o.dir + "/rig.yaml");
  }
  return std::make_pair(std::optional<HeadSpec>(), std::string());
}

// A simulation folder's frames (<sub>/frame_NNNN.*, in order) and its fps.
struct SimulationFrames {
  std::vector<StrandSet> frames;
  double fps = 30;
  size_t source_strands = 0;   // frame 0's before decimation
  std::vector<uint32_t> kept;  // frame 0's strands the decimation kept
};

// Each frame decimated as it is read (a frame of 20,000 strands is about 60 MB).
Result<SimulationFrames> ReadSimulation(const std::string& dir, const std::string& sub,
                                        int max_strands, int max_points, int threads) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/" + sub, ec))
    if (e.is_regular_file(ec) && e.path().filename().string().rfind("frame_", 0) == 0)
      files.push_back(e.path().string());
  if (ec || files.empty())
    return NotFound(dir + "/" + sub + ": no frame_NNNN strand files (a `hairrig simulate` output)");
  std::sort(files.begin(), files.end());
  SimulationFrames out;
  if (Result<nlohmann::json> summary = ReadJsonFile(dir + "/summary.json"); summary.ok()) {
    const JsonObject s(*summary, dir + "/summary.json");
    out.fps = s.NumberOr("fps", 30, {.min = 1e-3, .max = 1e4});
    HR_RETURN_IF_ERROR(s.status());
  }
  // Read in parallel (reading and parsing is most of an export's time); the
  // first error in frame order is returned.
  out.frames.resize(files.size());
  std::vector<Status> errors(files.size());
  ParallelFor(files.size(), threads, [&] {
    return [&](size_t i) {
      Result<StrandSet> frame = ReadStrands(files[i]);
      if (!frame.ok()) {
        errors[i] = frame.status();
        return;
      }
      if (i == 0) out.source_strands = frame->num_strands();
      out.frames[i] =
          DecimateStrands(*frame, max_strands, max_points, i == 0 ? &out.kept : nullptr);
    };
  });
  for (const Status& e : errors) HR_RETURN_IF_ERROR(e);
  return out;
}

// The simulation folder's name with every character but letters, digits, '_'
// and '-' made '_' (three.js and Blender rewrite other characters in node
// names, and the animation finds its node by name); "simulation" when empty.
std::string AnimationName(const std::string& simulation_dir) {
  std::string name = fs::path(simulation_dir).filename().string();
  if (name.empty()) name = fs::path(simulation_dir).parent_path().filename().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
  return name.empty() ? "simulation" : name;
}

std::string DisplayPath(const std::string& out_file) {
  const fs::path path(out_file);
  return (path.parent_path() / (path.stem().string() + ".display.glb")).string();
}

// What only the display level carries: the oriented points and the true strands.
struct DisplayExtras {
  std::vector<Eigen::Vector3f> points_mm;
  std::vector<std::array<uint8_t, 3>> point_colours;
  std::optional<StrandSet> truth;
};

// Whether the reconstruction's points are in the turntable frame (the frame
// the ground truth's strands are in), from reconstruction/summary.json.
bool ReconstructedInTurntableFrame(const std::string& dir) {
  Result<nlohmann::json> summary = ReadJsonFile(dir + "/reconstruction/summary.json");
  if (!summary.ok()) return false;
  const JsonObject s(*summary, dir + "/reconstruction/summary.json");
  return s.StringOr("object_frame", "") == "turntable" && s.ok();
}

// What the display adds is optional: a file that cannot be read is left out
// with a warning naming it, and the export goes on. `given_points`: the points
// when the caller holds them, else null.
DisplayExtras ReadDisplayExtras(const GltfExportOptions& o,
                                const std::vector<OrientedPoint>* given_points) {
  DisplayExtras extras;
  Result<std::vector<OrientedPoint>> read = std::vector<OrientedPoint>();
  if (o.display_cloud > 0 && given_points == nullptr && IsFile(o.dir + kPointsFile)) {
    read = ReadPointCloudPly(o.dir + kPointsFile);
    if (!read.ok()) LogWarning("export: the points are left out: " + read.status().ToString());
  }
  const std::vector<OrientedPoint>* points =
      given_points != nullptr ? given_points : (read.ok() ? &*read : nullptr);
  if (o.display_cloud > 0 && points != nullptr) {
    const size_t cap = static_cast<size_t>(o.display_cloud);
    const size_t stride = std::max<size_t>(1, (points->size() + cap - 1) / cap);
    for (size_t i = 0; i < points->size(); i += stride) {
      extras.points_mm.push_back((*points)[i].position_mm);
      extras.point_colours.push_back(DirectionColour((*points)[i].direction));
    }
  }
  // The truth is in the true turntable frame; the reconstruction in the
  // turntable frame its calibration found (the two differ by the calibration's
  // error, which the picture then shows) or in another frame altogether.
  if (IsFile(o.dir + kTruthStrandsFile) && ReconstructedInTurntableFrame(o.dir)) {
    Result<StrandSet> truth = ReadStrands(o.dir + kTruthStrandsFile);
    if (truth.ok())
      extras.truth = DecimateStrands(*truth, o.display_strands, o.display_points);
    else
      LogWarning("export: the ground truth is left out: " + truth.status().ToString());
  }
  return extras;
}

// Each strand's wisp (the guide it follows: the fitted model's
// cluster_of_strand), or none when the model is absent, unreadable or of other
// strands (a warning says which).
std::vector<uint32_t> ReadWisps(const GltfExportOptions& o, size_t strands) {
  const std::string path = o.model_file.empty() ? o.dir + kModelFile : o.model_file;
  if (o.model_file.empty() && !IsFile(path)) return {};
  Result<nlohmann::json> model = ReadJsonFile(path);
  std::vector<uint32_t> wisps;
  if (model.ok()) {
    const nlohmann::json clusters = model->value("cluster_of_strand", nlohmann::json());
    for (const nlohmann::json& c : clusters.is_array() ? clusters : nlohmann::json::array()) {
      if (!c.is_number_integer() || c.get<int64_t>() < 0 || c.get<int64_t>() >= (1 << 24)) break;
      wisps.push_back(c.get<uint32_t>());
    }
  }
  if (wisps.size() != strands || strands == 0) {
    LogWarning("export: no wisp ids: " +
               (model.ok() ? path + " gives " + std::to_string(wisps.size()) +
                                 " valid cluster_of_strand entries for the capture's " +
                                 std::to_string(strands) + " strands (fit from another file?)"
                           : model.status().ToString()));
    return {};
  }
  return wisps;
}

// wisps[kept[i]] for every i; empty when there are no wisps.
std::vector<uint32_t> WispsOf(const std::vector<uint32_t>& wisps,
                              const std::vector<uint32_t>& kept) {
  std::vector<uint32_t> out;
  if (wisps.empty()) return out;
  out.reserve(kept.size());
  for (const uint32_t k : kept) out.push_back(wisps[k]);
  return out;
}

// The simulation's animated strands and, where it wrote them, its guides.
struct Simulation {
  std::string name;  // the animation's; the guides' is name + "_guides"
  SimulationFrames strands, guides;
  std::vector<uint32_t> wisps;  // per strand of a frame, or empty
};

// `wisps`: the reconstruction's strands' (or empty); the frames take them
// when they hold as many strands (the simulation interpolated those).
Result<Simulation> ReadSimulationFolder(const GltfExportOptions& o,
                                        const std::vector<uint32_t>& wisps) {
  Simulation sim;
  if (o.simulation_dir.empty()) return sim;
  const int threads = ResolveThreads(o.threads);
  sim.name = AnimationName(o.simulation_dir);
  HR_ASSIGN_OR_RETURN(sim.strands, ReadSimulation(o.simulation_dir, "frames", o.animation_strands,
                                                  o.display_points, threads));
  if (sim.strands.source_strands == wisps.size()) sim.wisps = WispsOf(wisps, sim.strands.kept);
  if (fs::is_directory(o.simulation_dir + "/guides")) {
    HR_ASSIGN_OR_RETURN(sim.guides,
                        ReadSimulation(o.simulation_dir, "guides", kMaxGuides, 10000, threads));
    if (sim.guides.frames.size() != sim.strands.frames.size())
      return CorruptData(o.simulation_dir + ": " + std::to_string(sim.guides.frames.size()) +
                         " guide frames for " + std::to_string(sim.strands.frames.size()) +
                         " strand frames (an interrupted `hairrig simulate`? run it again)");
  }
  return sim;
}

// The animations of one level: the strands and, with `guides`, the guides,
// each `encoding`.
std::vector<GltfStrandAnimation> AnimationsOf(const Simulation& sim, GltfAnimationEncoding encoding,
                                              bool guides) {
  std::vector<GltfStrandAnimation> animations;
  auto add = [&](const std::string& name, const SimulationFrames& frames,
                 std::array<float, 4> colour, const std::vector<uint32_t>* wisps) {
    if (frames.frames.empty()) return;
    GltfStrandAnimation a{.name = name,
                          .frames = {},
                          .fps = frames.fps,
                          .colour = colour,
                          .encoding = encoding,
                          .wisps = wisps};
    for (const StrandSet& f : frames.frames) a.frames.push_back(&f);
    animations.push_back(std::move(a));
  };
  add(sim.name, sim.strands, GltfStrandAnimation{}.colour,
      sim.wisps.empty() ? nullptr : &sim.wisps);
  if (guides) add(sim.name + "_guides", sim.guides, kGuideColour, nullptr);
  return animations;
}

// The scene of one level: `strands`, the head, the animations, and the display's extras.
GltfScene SceneOf(const StrandSet& strands, const std::vector<uint32_t>& wisps,
                  const TriangleMesh* head, std::vector<GltfStrandAnimation> animations,
                  const DisplayExtras* extras = nullptr) {
  GltfScene scene;
  scene.strand_sets.push_back(
      {.name = "strands", .strands = &strands, .wisps = wisps.empty() ? nullptr : &wisps});
  if (extras != nullptr && extras->truth && !extras->truth->point_counts.empty())
    scene.strand_sets.push_back(
        {.name = "truth", .strands = &*extras->truth, .colour = {0.1f, 0.6f, 0.2f, 1.0f}});
  if (extras != nullptr && !extras->points_mm.empty())
    scene.point_clouds.push_back(
        {.name = "points", .points_mm = &extras->points_mm, .colours = &extras->point_colours});
  if (head != nullptr) scene.meshes.push_back({.name = "head", .mesh = head});
  scene.animations = std::move(animations);
  return scene;
}

}  // namespace

Status GltfExportOptions::Check() const {
  if (dir.empty()) return InvalidArgument("export: the capture folder is required");
  if (display_strands < 1 || display_strands > 1000000)
    return InvalidArgument("export: --display-strands must be in 1 .. 1,000,000");
  if (display_points < 2 || display_points > 10000)
    return InvalidArgument("export: --display-points must be in 2 .. 10,000");
  if (threads < 0) return InvalidArgument("export: --threads must be 0 (one per core) or more");
  if (animation_strands < 1 || animation_strands > 1000000)
    return InvalidArgument("export: --animation-strands must be in 1 .. 1,000,000");
  if (display_cloud < 0 || display_cloud > 10000000)
    return InvalidArgument("export: --display-cloud must be in 0 .. 10,000,000");
  return Status::Ok();
}

StrandSet DecimateStrands(const StrandSet& strands, int max_strands, int max_points,
                          std::vector<uint32_t>* kept_strands) {
  if (kept_strands != nullptr) kept_strands->clear();
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
      if (kept_strands != nullptr) kept_strands->push_back(static_cast<uint32_t>(s));
    }
    first += count;
  }
  return out;
}

std::array<uint8_t, 3> DirectionColour(const Eigen::Vector3f& direction) {
  const Eigen::Vector3f d = direction.cwiseAbs().cwiseMin(1.0f);
  auto channel = [](float v) { return static_cast<uint8_t>(std::lround(255.0f * v)); };
  return {channel(d.x()), channel(d.y()), channel(d.z())};
}

nlohmann::json GltfExportSummary::ToJson() const {
  auto level = [](const GltfWriteSummary& s) {
    return nlohmann::json{{"path", s.path},         {"bytes", s.bytes},
                          {"strands", s.strands},   {"vertices", s.vertices},
                          {"segments", s.segments}, {"frames", s.frames}};
  };
  return {{"full", level(full)},
          {"display", level(display)},
          {"head", head_source},
          {"truth_strands", truth_strands},
          {"cloud_points", cloud_points},
          {"guides", guides},
          {"wisps", wisps}};
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
  if (wisps > 0) text += StringPrintf("  wisp ids of %lld wisps\n", static_cast<long long>(wisps));
  if (guides > 0)
    text += StringPrintf("  full: %lld animated guides\n", static_cast<long long>(guides));
  if (cloud_points > 0)
    text += StringPrintf("  display: %lld oriented points\n", static_cast<long long>(cloud_points));
  if (truth_strands > 0)
    text += StringPrintf("  display: %lld true strands (ground truth)\n",
                         static_cast<long long>(truth_strands));
  return text;
}

Result<GltfExportSummary> ExportCaptureGltf(const GltfExportOptions& o,
                                            const GltfExportInputs& inputs) {
  HR_RETURN_IF_ERROR(o.Check());
  const std::string out_file =
      o.out_file.empty() ? o.dir + "/reconstruction/strands/hair.glb" : o.out_file;
  StrandSet read_strands;
  if (inputs.strands == nullptr) {
    HR_ASSIGN_OR_RETURN(read_strands, ReadStrands(o.dir + kStrandsFile));
  }
  const StrandSet& strands = inputs.strands != nullptr ? *inputs.strands : read_strands;
  HR_ASSIGN_OR_RETURN(const auto head, FindHead(o));
  GltfExportSummary summary;
  summary.head_source = head.second;
  std::unique_ptr<HeadModel> head_model;
  if (head.first) {
    HR_ASSIGN_OR_RETURN(head_model, HeadModel::Build(*head.first));
  }
  const TriangleMesh* head_mesh = head_model ? &head_model->mesh() : nullptr;

  const std::vector<uint32_t> wisps = ReadWisps(o, strands.num_strands());
  HR_ASSIGN_OR_RETURN(const Simulation simulation, ReadSimulationFolder(o, wisps));
  summary.wisps = wisps.empty() ? 0 : *std::max_element(wisps.begin(), wisps.end()) + 1;
  summary.guides = simulation.guides.frames.empty()
                       ? 0
                       : static_cast<int64_t>(simulation.guides.frames[0].num_strands());
  if (!o.display_only) {
    HR_ASSIGN_OR_RETURN(
        summary.full,
        WriteGlb(out_file, SceneOf(strands, wisps, head_mesh,
                                   AnimationsOf(simulation, o.animation_encoding, true))));
  }
  std::vector<uint32_t> kept;
  const StrandSet display = DecimateStrands(strands, o.display_strands, o.display_points, &kept);
  const DisplayExtras extras = ReadDisplayExtras(o, inputs.points);
  summary.cloud_points = static_cast<int64_t>(extras.points_mm.size());
  if (extras.truth) summary.truth_strands = static_cast<int64_t>(extras.truth->point_counts.size());
  HR_ASSIGN_OR_RETURN(
      summary.display,
      WriteGlb(
          DisplayPath(out_file),
          SceneOf(display, WispsOf(wisps, kept), head_mesh,
                  AnimationsOf(simulation, GltfAnimationEncoding::kFrameNodes, false), &extras)));
  return summary;
}

}  // namespace hairrig
