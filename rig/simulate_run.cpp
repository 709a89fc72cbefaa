#include "rig/simulate_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/file_util.h"
#include "core/head_config.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/log.h"
#include "core/statistics.h"
#include "core/strand_io.h"
#include "core/string_format.h"
#include "rig/rig_config.h"
#include "rig/simulation_preview.h"
#include "simulation/guide_interpolation.h"

namespace hairrig {

namespace {

namespace fs = std::filesystem;

constexpr int kPointsPerElement = 4;

StrandSet ToStrandSet(const std::vector<std::vector<Eigen::Vector3d>>& curves) {
  StrandSet set;
  for (const auto& curve : curves) {
    std::vector<Eigen::Vector3f> points;
    for (const auto& p : curve) points.push_back(p.cast<float>());
    set.AddStrand(points);
  }
  return set;
}

// The model's source strands, as recorded (relative to where `fit` ran) or
// beside the model file. Empty when neither can be read.
StrandSet ReadSourceStrands(const HelixModel& model, const std::string& model_path) {
  if (model.source.empty()) return {};
  for (const fs::path& candidate :
       {fs::path(model.source), fs::path(model_path).parent_path() / model.source}) {
    if (!fs::exists(candidate)) continue;
    auto strands = ReadStrands(candidate.string());
    if (strands.ok()) return *std::move(strands);
    LogWarning(candidate.string() + ": " + strands.status().message());
  }
  LogWarning("the model's source strands (" + model.source +
             ") cannot be read: writing the guides only");
  return {};
}

Result<std::string> ScenePath(const SimulateRunOptions& o) {
  if (!o.scene_file.empty()) return o.scene_file;
  return EtcPath("scenes/default.yaml");
}

// The head file's head when one is given, else the scene's.
Result<HeadSpec> LoadHead(const SimulateRunOptions& o, const std::string& scene_path) {
  if (!o.head_file.empty()) return LoadHeadFile(o.head_file);
  return ReadHeadOfFile(scene_path);
}

Result<HairSimulationOptions> MakeSimulationOptions(const SimulateRunOptions& o,
                                                    const HeadSpec& head) {
  HairSimulationOptions s;
  s.scenario = o.scenario;
  s.dynamics.time_step_s = o.time_step_s;
  s.dynamics.solver = o.solver;
  s.threads = o.threads;
  s.up = o.up.normalized();
  s.has_head = o.head_contact;
  s.head_center_mm = head.center_turntable_mm;
  s.head_radii_mm = head.radii_mm;
  if (s.has_head && !o.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(std::unique_ptr<HeadModel> surface, HeadModel::Build(head));
    s.head_surface = std::move(surface);
  }
  return s;
}

Status WritePreview(StrandPreviewer& previewer, const StrandSet& strands, const std::string& path) {
  HR_ASSIGN_OR_RETURN(const cv::Mat image, previewer.Draw(strands));
  return WriteImageAtomic(path, image);
}

// frames/, previews/ and, for interpolated strands, guides/.
Status CreateOutputFolders(const std::string& out_dir, bool interpolated) {
  for (const char* sub : {"frames", "previews", interpolated ? "guides" : "frames"}) {
    std::error_code ec;
    fs::create_directories(fs::path(out_dir) / sub, ec);
    if (ec) return IoError(out_dir + "/" + sub + ": cannot create (" + ec.message() + ")");
  }
  return Status::Ok();
}

// What the frame loop works with.
struct SimulateSetup {
  HairSimulationOptions options;
  std::unique_ptr<HairSimulation> sim;
  std::vector<std::vector<Eigen::Vector3d>> guides_rest;
  size_t full_strands = 0;
  std::unique_ptr<GuideInterpolation> interpolation;  // null: the guides are written
  std::vector<double> rest_lengths_mm;                // per written strand, at rest
  std::unique_ptr<StrandPreviewer> previewer;         // null: no previews
};

Result<SimulateSetup> Setup(const SimulateRunOptions& o) {
  HR_ASSIGN_OR_RETURN(const HelixModel model, ReadHelixModel(o.model_file));
  HR_ASSIGN_OR_RETURN(const std::string scene_path, ScenePath(o));
  HR_ASSIGN_OR_RETURN(const HeadSpec head, LoadHead(o, scene_path));
  SimulateSetup setup;
  HR_ASSIGN_OR_RETURN(setup.options, MakeSimulationOptions(o, head));
  HR_ASSIGN_OR_RETURN(setup.sim, HairSimulation::Create(model, setup.options));
  setup.guides_rest = setup.sim->GuideCurves(kPointsPerElement);
  const StrandSet full = o.guides_only ? StrandSet{} : ReadSourceStrands(model, o.model_file);
  setup.full_strands = full.num_strands();
  if (full.num_strands() > 0) {
    GuideInterpolationOptions blend;
    blend.keep_lengths = o.keep_lengths;
    HR_ASSIGN_OR_RETURN(GuideInterpolation built,
                        GuideInterpolation::Build(full, setup.guides_rest, blend));
    setup.interpolation = std::make_unique<GuideInterpolation>(std::move(built));
    setup.rest_lengths_mm = full.StrandLengths();
  } else {
    setup.rest_lengths_mm = ToStrandSet(setup.guides_rest).StrandLengths();
  }
  if (o.preview_every > 0) {
    HR_ASSIGN_OR_RETURN(setup.previewer, MakeStrandPreviewer(scene_path, head));
  }
  return setup;
}

// The written strands' lengths over their rest lengths: its 99th percentile
// and largest value raise the summary's.
void TrackStretch(const std::vector<double>& rest_lengths_mm, const StrandSet& strands,
                  SimulateRunSummary* s) {
  const std::vector<double> lengths = strands.StrandLengths();
  std::vector<double> ratios;
  for (size_t i = 0; i < lengths.size() && i < rest_lengths_mm.size(); ++i)
    if (rest_lengths_mm[i] > 0) ratios.push_back(lengths[i] / rest_lengths_mm[i]);
  if (ratios.empty()) return;
  s->strand_stretch_p99 = std::max(s->strand_stretch_p99, Quantile(ratios, 0.99));
  s->strand_stretch_max =
      std::max(s->strand_stretch_max, *std::max_element(ratios.begin(), ratios.end()));
}

// Frame f's strand file and, every preview_every frames, its preview.
Status WriteFrame(const SimulateRunOptions& o, SimulateSetup& setup,
                  const std::vector<std::vector<Eigen::Vector3d>>& guides, int f,
                  SimulateRunSummary* s) {
  StrandSet strands;
  const std::string name = StringPrintf("frame_%04d", f);
  if (setup.interpolation) {
    HR_ASSIGN_OR_RETURN(strands, setup.interpolation->Apply(guides));
    HR_RETURN_IF_ERROR(WriteStrands(o.out_dir + "/guides/" + name + ".hair", ToStrandSet(guides)));
  } else {
    strands = ToStrandSet(guides);
  }
  TrackStretch(setup.rest_lengths_mm, strands, s);
  HR_RETURN_IF_ERROR(WriteStrands(o.out_dir + "/frames/" + name + ".hair", strands));
  if (setup.previewer && f % o.preview_every == 0) {
    HR_RETURN_IF_ERROR(
        WritePreview(*setup.previewer, strands, o.out_dir + "/previews/" + name + ".png"));
  }
  return Status::Ok();
}

}  // namespace

Status SimulateRunOptions::Check() const {
  if (model_file.empty()) return InvalidArgument("simulate: model_file is required");
  if (out_dir.empty()) return InvalidArgument("simulate: out_dir (--out) is required");
  if (!(seconds > 0) || !(fps > 0) || !std::isfinite(seconds) || !std::isfinite(fps)) {
    return InvalidArgument("--seconds and --fps must be positive");
  }
  if (!(time_step_s > 0) || !std::isfinite(time_step_s)) {
    return InvalidArgument("--dt (time_step_s) must be a positive number of seconds");
  }
  if (!up.allFinite() || up.norm() < 1e-9)
    return InvalidArgument("--up must be a non-zero direction");
  if (preview_every < 0) return InvalidArgument("--preview-every must be 0 (no previews) or more");
  if (threads < 0) return InvalidArgument("--threads must be 0 (one per core) or more");
  return Status::Ok();
}

nlohmann::json SimulateRunSummary::ToJson() const {
  return {{"out", out_dir},
          {"model", model_file},
          {"scenario", ScenarioName(scenario)},
          {"seconds", seconds},
          {"fps", fps},
          {"frames", frames},
          {"time_step_s", time_step_s},
          {"guides", guides},
          {"strands", strands},
          {"interpolated", interpolated},
          {"interpolation_rest_fit_rms_mm", interpolation_rest_fit_rms_mm},
          {"head_contact", head_contact},
          {"steps", stats.steps},
          {"dynamics_wall_s", dynamics_wall_s},
          {"steps_per_s",
           dynamics_wall_s > 0 ? static_cast<double>(stats.steps) / dynamics_wall_s : 0.0},
          {"mean_solver_iterations", stats.mean_solver_iterations},
          {"contact_samples", stats.contact_samples},
          {"max_tip_move_mm", max_tip_move_mm},
          {"strand_stretch_p99", strand_stretch_p99},
          {"strand_stretch_max", strand_stretch_max},
          {"max_inverse_statics_change_per_m", stats.max_inverse_statics_change}};
}

std::string SimulateRunSummary::BriefReport() const {
  const double steps_per_s =
      dynamics_wall_s > 0 ? static_cast<double>(stats.steps) / dynamics_wall_s : 0.0;
  return StringPrintf("%s: %s, %.2f s at %.0f fps: %d frames of %zu strands driven by %d guides\n",
                      out_dir.c_str(), ScenarioName(scenario), seconds, fps, frames, strands,
                      guides) +
         StringPrintf(
             "  %lld steps of %.4f s, %.0f steps/s; tips moved up to %.1f mm; strands' length "
             "over rest %.3f (99th percentile), %.3f (largest); frames/ and previews/ beside "
             "summary.json\n",
             stats.steps, time_step_s, steps_per_s, max_tip_move_mm, strand_stretch_p99,
             strand_stretch_max);
}

Result<SimulateRunSummary> SimulateRun(const SimulateRunOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  if (fs::exists(o.out_dir) && !fs::is_empty(o.out_dir)) {
    return FailedPrecondition(o.out_dir +
                              " already exists and is not empty: choose a new --out folder");
  }
  HR_ASSIGN_OR_RETURN(SimulateSetup setup, Setup(o));
  HR_RETURN_IF_ERROR(CreateOutputFolders(o.out_dir, setup.interpolation != nullptr));
  SimulateRunSummary s;
  s.frames = static_cast<int>(std::lround(o.seconds * o.fps)) + 1;
  for (int f = 0; f < s.frames; ++f) {
    if (f > 0) {
      const auto start = std::chrono::steady_clock::now();
      HR_RETURN_IF_ERROR(setup.sim->Advance(1.0 / o.fps).WithContext("frame " + std::to_string(f)));
      s.dynamics_wall_s +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    const auto guides = setup.sim->GuideCurves(kPointsPerElement);
    for (size_t g = 0; g < guides.size(); ++g)
      s.max_tip_move_mm =
          std::max(s.max_tip_move_mm, (guides[g].back() - setup.guides_rest[g].back()).norm());
    HR_RETURN_IF_ERROR(WriteFrame(o, setup, guides, f, &s));
    if (f % 10 == 0)
      LogInfo("simulate: frame " + std::to_string(f) + " of " + std::to_string(s.frames));
  }
  s.out_dir = o.out_dir;
  s.model_file = o.model_file;
  s.scenario = o.scenario;
  s.seconds = o.seconds;
  s.fps = o.fps;
  s.time_step_s = setup.options.dynamics.time_step_s;
  s.guides = setup.sim->num_guides();
  s.interpolated = setup.interpolation != nullptr;
  s.strands = s.interpolated ? setup.full_strands : static_cast<size_t>(s.guides);
  s.interpolation_rest_fit_rms_mm = s.interpolated ? setup.interpolation->rest_fit_rms_mm() : 0.0;
  s.head_contact = setup.options.has_head;
  s.stats = setup.sim->stats();
  HR_RETURN_IF_ERROR(WriteFileAtomic(o.out_dir + "/summary.json", s.ToJson().dump(2) + "\n"));
  return s;
}

}  // namespace hairrig
