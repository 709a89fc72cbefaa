// `hairrig simulate MODEL --out DIR`: super-helix dynamics of a fitted model
// (simulation/hair_simulation.h), the full hairstyle interpolated from the
// guides (simulation/guide_interpolation.h), a strand file and a preview per
// frame, and a summary.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/file_util.h"
#include "core/head_config.h"
#include "core/head_model.h"
#include "core/log.h"
#include "core/strand_io.h"
#include "rig/cli.h"
#include "rig/rig_config.h"
#include "sim_hw/renderer.h"
#include "simulation/guide_interpolation.h"
#include "simulation/hair_simulation.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

struct SimulateArgs {
  std::string model;
  std::string out;
  std::string scenario = "gravity";
  double seconds = 2;
  double fps = 30;
  double time_step_s = 1.0 / 240;
  std::string scene;
  std::string head_file;
  bool no_head = false;
  std::vector<double> up{0, 0, 1};
  int preview_every = 1;
  bool guides_only = false;
  std::string solver = "cholesky";
};

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
  for (const fs::path& candidate : {fs::path(model.source), fs::path(model_path).parent_path() / model.source}) {
    if (!fs::exists(candidate)) continue;
    auto strands = ReadStrands(candidate.string());
    if (strands.ok()) return *std::move(strands);
    LogWarning(candidate.string() + ": " + strands.status().message());
  }
  LogWarning("the model's source strands (" + model.source + ") cannot be read: writing the guides only");
  return {};
}

Result<HairSimulationOptions> MakeOptions(const SimulateArgs& a, const Scene& scene) {
  HairSimulationOptions o;
  HR_ASSIGN_OR_RETURN(o.scenario, ParseScenario(a.scenario));
  o.dynamics.time_step_s = a.time_step_s;
  if (a.solver != "cg" && a.solver != "cholesky") return InvalidArgument("--solver must be cg or cholesky");
  o.dynamics.solver = a.solver == "cg" ? LinearSolver::kConjugateGradient : LinearSolver::kCholesky;
  const Eigen::Vector3d up(a.up[0], a.up[1], a.up[2]);
  if (!up.allFinite() || up.norm() < 1e-9) return InvalidArgument("--up must be a non-zero direction");
  o.up = up.normalized();
  o.has_head = !a.no_head;
  o.head_center_mm = scene.head.center_turntable_mm;
  o.head_radii_mm = scene.head.radii_mm;
  if (o.has_head && !a.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(std::unique_ptr<HeadModel> head, HeadModel::Build(scene.head));
    o.head_surface = std::move(head);
  }
  return o;
}

Status WritePreview(Renderer* renderer, const StrandSet& strands, const std::string& path) {
  renderer->SetStrands(strands);
  RenderOptions options;
  options.noise = false;
  HR_ASSIGN_OR_RETURN(RenderedView view, renderer->Render(0, 0.0, options));
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", view.image, png)) return Internal(path + ": PNG encoding failed");
  return WriteFileAtomic(path, png.data(), png.size());
}

Result<nlohmann::json> RunSimulate(const SimulateArgs& a) {
  if (!(a.seconds > 0) || !(a.fps > 0) || !std::isfinite(a.seconds) || !std::isfinite(a.fps)) {
    return InvalidArgument("--seconds and --fps must be positive");
  }
  if (fs::exists(a.out) && !fs::is_empty(a.out)) {
    return FailedPrecondition(a.out + " already exists and is not empty: choose a new --out folder");
  }
  HR_ASSIGN_OR_RETURN(HelixModel model, ReadHelixModel(a.model));
  std::string scene_path = a.scene;
  if (scene_path.empty()) {
    HR_ASSIGN_OR_RETURN(scene_path, EtcPath("scenes/default.yaml"));
  }
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(scene_path));
  if (!a.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(scene.head, LoadHeadFile(a.head_file));  // for contact and in the previews
  }
  HR_ASSIGN_OR_RETURN(HairSimulationOptions options, MakeOptions(a, scene));
  HR_ASSIGN_OR_RETURN(std::unique_ptr<HairSimulation> sim, HairSimulation::Create(model, options));

  const auto guides_rest = sim->GuideCurves(kPointsPerElement);
  const StrandSet full = a.guides_only ? StrandSet{} : ReadSourceStrands(model, a.model);
  std::unique_ptr<GuideInterpolation> interpolation;
  if (full.num_strands() > 0) {
    HR_ASSIGN_OR_RETURN(GuideInterpolation built, GuideInterpolation::Build(full, guides_rest, {}));
    interpolation = std::make_unique<GuideInterpolation>(std::move(built));
  }
  std::unique_ptr<Renderer> renderer;
  if (a.preview_every > 0) {
    scene.wig.num_strands = 1;  // replaced by the simulated strands
    HR_ASSIGN_OR_RETURN(renderer, Renderer::Create(scene));
  }
  for (const char* sub : {"frames", "previews"}) {
    std::error_code ec;
    fs::create_directories(fs::path(a.out) / sub, ec);
    if (ec) return IoError(a.out + "/" + sub + ": cannot create (" + ec.message() + ")");
  }

  const int frames = static_cast<int>(std::lround(a.seconds * a.fps)) + 1;
  double dynamics_s = 0, max_tip_move_mm = 0;
  for (int f = 0; f < frames; ++f) {
    if (f > 0) {
      const auto start = std::chrono::steady_clock::now();
      HR_RETURN_IF_ERROR(sim->Advance(1.0 / a.fps).WithContext("frame " + std::to_string(f)));
      dynamics_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    const auto guides = sim->GuideCurves(kPointsPerElement);
    for (size_t g = 0; g < guides.size(); ++g) {
      max_tip_move_mm = std::max(max_tip_move_mm, (guides[g].back() - guides_rest[g].back()).norm());
    }
    StrandSet strands;
    if (interpolation) {
      HR_ASSIGN_OR_RETURN(strands, interpolation->Apply(guides));
    } else {
      strands = ToStrandSet(guides);
    }
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d", f);
    HR_RETURN_IF_ERROR(WriteStrands(a.out + "/frames/" + name + ".hair", strands));
    if (renderer && f % a.preview_every == 0) {
      HR_RETURN_IF_ERROR(WritePreview(renderer.get(), strands, a.out + "/previews/" + name + ".png"));
    }
    if (f % 10 == 0) LogInfo("simulate: frame " + std::to_string(f) + " of " + std::to_string(frames));
  }
  const HairSimulationStats& stats = sim->stats();
  nlohmann::json summary{{"out", a.out},
                         {"model", a.model},
                         {"scenario", ScenarioName(options.scenario)},
                         {"seconds", a.seconds},
                         {"fps", a.fps},
                         {"frames", frames},
                         {"time_step_s", options.dynamics.time_step_s},
                         {"guides", sim->num_guides()},
                         {"strands", interpolation ? full.num_strands() : static_cast<size_t>(sim->num_guides())},
                         {"interpolated", interpolation != nullptr},
                         {"interpolation_rest_fit_rms_mm", interpolation ? interpolation->rest_fit_rms_mm() : 0.0},
                         {"head_contact", options.has_head},
                         {"steps", stats.steps},
                         {"dynamics_wall_s", dynamics_s},
                         {"steps_per_s", dynamics_s > 0 ? static_cast<double>(stats.steps) / dynamics_s : 0.0},
                         {"mean_solver_iterations", stats.mean_solver_iterations},
                         {"contact_samples", stats.contact_samples},
                         {"max_tip_move_mm", max_tip_move_mm},
                         {"max_inverse_statics_change_per_m", stats.max_inverse_statics_change}};
  HR_RETURN_IF_ERROR(WriteFileAtomic(a.out + "/summary.json", summary.dump(2) + "\n"));
  return summary;
}

void PrintSimulate(const nlohmann::json& j) {
  std::printf("%s: %s, %.2f s at %.0f fps: %d frames of %zu strands driven by %d guides\n",
              j["out"].get<std::string>().c_str(), j["scenario"].get<std::string>().c_str(), j["seconds"].get<double>(),
              j["fps"].get<double>(), j["frames"].get<int>(), j["strands"].get<size_t>(), j["guides"].get<int>());
  std::printf("  %lld steps of %.4f s, %.0f steps/s; tips moved up to %.1f mm; frames/ and previews/ beside summary.json\n",
              j["steps"].get<long long>(), j["time_step_s"].get<double>(), j["steps_per_s"].get<double>(),
              j["max_tip_move_mm"].get<double>());
}

}  // namespace

void AddSimulateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("simulate", "Super-helix dynamics of a fitted model: strand files and previews per frame");
  auto args = std::make_shared<SimulateArgs>();
  cmd->add_option("MODEL", args->model, "model file written by `hairrig fit`")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "folder to write (frames/, previews/, summary.json)")->required();
  cmd->add_option("--scenario", args->scenario, "gravity, head-shake or wind")->capture_default_str();
  cmd->add_option("--seconds", args->seconds, "simulated time")->capture_default_str();
  cmd->add_option("--fps", args->fps, "frames written per simulated second")->capture_default_str();
  cmd->add_option("--dt", args->time_step_s, "time step of the dynamics (s)")->capture_default_str();
  cmd->add_option("--solver", args->solver, "linear solver of Eq. 11: cg (paper) or cholesky")->capture_default_str();
  cmd->add_option("--scene", args->scene, "scene giving the head and the preview camera (default: etc/scenes/default.yaml)");
  cmd->add_option("--head", args->head_file,
                  "head file (core/head_config.h) for contact with its surface and in the previews, e.g. the one the "
                  "strands were reconstructed on (default: the scene's ellipsoid for contact)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-head", args->no_head, "no contact with the head");
  cmd->add_option("--up", args->up, "world up direction (x y z)")->expected(3)->capture_default_str();
  cmd->add_option("--preview-every", args->preview_every, "render a preview every N frames (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--guides-only", args->guides_only, "write the guides, not the interpolated full hairstyle");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunSimulate(*args); };
    dispatch.print_human = PrintSimulate;
  });
}

}  // namespace hairrig
