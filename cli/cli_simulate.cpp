// `hairrig simulate MODEL --out DIR`: super-helix dynamics of a fitted model,
// a strand file and a preview per frame, and a summary (rig/simulate_run.h).
#include <CLI/CLI.hpp>

#include "cli/cli.h"
#include "rig/simulate_run.h"

namespace hairrig {
namespace {

struct SimulateArgs {
  SimulateRunOptions options;
  std::string scenario = "gravity";
  std::string solver = "cholesky";
  bool no_head = false;
  std::vector<double> up{0, 0, 1};
};

// The options from the arguments CLI11 does not map itself.
Result<SimulateRunOptions> ParseSimulateArgs(const SimulateArgs& a) {
  SimulateRunOptions options = a.options;
  HR_ASSIGN_OR_RETURN(options.scenario, ParseScenario(a.scenario));
  if (a.solver != "cg" && a.solver != "cholesky")
    return InvalidArgument("--solver must be cg or cholesky");
  options.solver = a.solver == "cg" ? LinearSolver::kConjugateGradient : LinearSolver::kCholesky;
  options.head_contact = !a.no_head;
  options.up = Eigen::Vector3d(a.up[0], a.up[1], a.up[2]);
  return options;
}

}  // namespace

void AddSimulateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "simulate", "Super-helix dynamics of a fitted model: strand files and previews per frame");
  auto args = std::make_shared<SimulateArgs>();
  SimulateRunOptions& o = args->options;
  cmd->add_option("MODEL", o.model_file, "model file written by `hairrig fit`")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o.out_dir, "folder to write (frames/, previews/, summary.json)")
      ->required();
  cmd->add_option("--scenario", args->scenario, "gravity, head-shake or wind")
      ->capture_default_str();
  cmd->add_option("--seconds", o.seconds, "simulated time")->capture_default_str();
  cmd->add_option("--fps", o.fps, "frames written per simulated second")->capture_default_str();
  cmd->add_option("--dt", o.time_step_s, "time step of the dynamics (s)")->capture_default_str();
  cmd->add_option("--solver", args->solver, "linear solver of Eq. 11: cg (paper) or cholesky")
      ->capture_default_str();
  cmd->add_option(
      "--scene", o.scene_file,
      "scene giving the head and the preview camera (default: etc/scenes/default.yaml)");
  cmd->add_option("--head", o.head_file,
                  "head file (core/head_config.h) for contact with its surface and in the "
                  "previews, e.g. the one the strands were reconstructed on (default: the scene's "
                  "ellipsoid for contact)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-head", args->no_head, "no contact with the head");
  cmd->add_option("--up", args->up, "world up direction (x y z)")
      ->expected(3)
      ->capture_default_str();
  cmd->add_option("--preview-every", o.preview_every, "render a preview every N frames (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--threads", o.threads, "guides stepped in parallel (0: one thread per core)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--guides-only", o.guides_only,
                "write the guides, not the interpolated full hairstyle");
  cmd->add_flag("--keep-lengths,!--plain-blend", o.keep_lengths,
                "interpolated strands keep their rest segment lengths (default; "
                "--plain-blend: the guides' blend alone)");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    DispatchSummary(dispatch, [args]() -> Result<SimulateRunSummary> {
      HR_ASSIGN_OR_RETURN(const SimulateRunOptions options, ParseSimulateArgs(*args));
      return SimulateRun(options);
    });
  });
}

}  // namespace hairrig
