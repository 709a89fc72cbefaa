// `hairrig sim render | charuco | serve`: the simulated rig's renders and
// protocol-level simulators (sim_hw/view_set.h, sim_hw/charuco_views.h,
// sim_hw/sim_serve.h).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/cli.h"
#include "rig/rig_config.h"
#include "sim_hw/charuco_views.h"
#include "sim_hw/sim_serve.h"
#include "sim_hw/view_set.h"

namespace hairrig {
namespace {

// `path`, or the project's file `etc_relative` when it is empty.
Result<std::string> OrEtcFile(const std::string& path, const std::string& etc_relative) {
  if (!path.empty()) return path;
  return EtcPath(etc_relative);
}

Result<std::string> SceneOrDefault(const std::string& scene) {
  return OrEtcFile(scene, "scenes/default.yaml");
}

void AddChArUcoCommand(CLI::App& sim, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd =
      sim.add_subcommand("charuco",
                         "Render what a technician records to calibrate each camera's intrinsics "
                         "alone: a ChArUco board held in front of it (OUT/<serial>/)");
  auto options = std::make_shared<ChArUcoSetsOptions>();
  cmd->add_option("--out", options->out_dir, "output folder")->required();
  cmd->add_option("--scene", options->scene_file, "scene file (default: etc/scenes/default.yaml)");
  cmd->add_option("--board", options->board_file,
                  "ChArUco board file (default: etc/charuco-board.yaml)");
  cmd->add_option("--camera", options->serials, "only this camera (serial); repeat for several");
  cmd->add_option("--views", options->views, "images per camera")
      ->check(CLI::Range(1, 500))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "board poses and sensor noise")->capture_default_str();
  cmd->add_option("--threads", options->threads, "cameras rendered at once")
      ->check(CLI::Range(1, 64));
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([options, &dispatch] {
    DispatchSummary(dispatch, [options]() -> Result<ChArUcoSetsSummary> {
      ChArUcoSetsOptions o = *options;
      HR_ASSIGN_OR_RETURN(o.scene_file, SceneOrDefault(o.scene_file));
      HR_ASSIGN_OR_RETURN(o.board_file, OrEtcFile(o.board_file, "charuco-board.yaml"));
      return WriteChArUcoSets(o);
    });
  });
}

void PrintEndpoints(const std::string& endpoints) {
  std::fputs(endpoints.c_str(), stdout);
  std::fflush(stdout);
}

void AddServeCommand(CLI::App& sim, CommonOptions& common, Dispatch& dispatch) {
  auto* serve = sim.add_subcommand(
      "serve", "Run the protocol-level simulators for outside tools until Ctrl-C");
  auto options = std::make_shared<SimServeOptions>();
  serve->add_option("--scene", options->scene_file,
                    "scene file (default: etc/scenes/default.yaml)");
  serve->add_option("--serial", options->turntable_serial,
                    "the simulated turntable controller's serial number");
  serve
      ->add_option("--modbus-port", options->modbus_port,
                   "Modbus TCP port on 127.0.0.1 (default: a free one)")
      ->check(CLI::Range(0, 65535));
  serve->add_option("--slave-id", options->slave_id, "Modbus unit id")->check(CLI::Range(1, 247));
  serve
      ->add_option("--time-scale", options->time_scale,
                   "device seconds x this = wall seconds (default 1: real time)")
      ->check(CLI::PositiveNumber);
  serve->add_flag("!--no-rtu", options->rtu, "do not serve Modbus RTU on a pseudo-terminal");
  serve->add_flag("!--no-dslr", options->dslr,
                  "do not serve the simulated DSLRs (one per scene camera)");
  serve->add_flag(
      "!--no-gige", options->gige,
      "do not serve the simulated GigE Vision camera (the scene's last camera, on 127.0.0.1:3956)");
  serve->add_flag("--json", common.json, "print the closing summary as one JSON object");
  serve->callback([options, &dispatch] {
    options->on_serving = PrintEndpoints;
    DispatchSummary(dispatch, [options]() -> Result<SimServeSummary> {
      SimServeOptions o = *options;
      HR_ASSIGN_OR_RETURN(o.scene_file, SceneOrDefault(o.scene_file));
      return ServeSimulatedDevices(o);
    });
  });
}

// --view fills `view`; --all takes the scene, output and noise from it too.
struct RenderArgs {
  RenderViewFileOptions view;
  RenderSceneViewsOptions views;
  bool all = false;
  std::vector<int> crop;  // x, y, width, height (px); empty = the whole view
};

void AddRenderCommand(CLI::App& sim, CommonOptions& common, Dispatch& dispatch) {
  auto* render = sim.add_subcommand(
      "render", "Render one view (--view N --out FILE) or all (--all --out DIR)");
  auto args = std::make_shared<RenderArgs>();
  args->view.view = -1;
  render->add_option("--scene", args->view.scene_file,
                     "scene file (default: etc/scenes/default.yaml)");
  auto* view = render->add_option("--view", args->view.view, "view index: stop * cameras + camera");
  auto* all =
      render->add_flag("--all", args->all, "every view, a contact sheet and the ground truth");
  view->excludes(all);
  render->add_option("--out", args->view.out_file, "output image (--view) or folder (--all)")
      ->required();
  render->add_flag("!--no-noise", args->view.noise, "render without sensor noise");
  render
      ->add_option("--crop", args->crop,
                   "with --view: write only the pixels X,Y,WIDTH,HEIGHT, at full resolution")
      ->delimiter(',')
      ->expected(4)
      ->excludes(all);
  render->add_option("--threads", args->views.render.threads, "render threads for --all")
      ->check(CLI::Range(1, 64));
  render->add_flag("--json", common.json, "print the summary as one JSON object");
  render->callback([args, &dispatch] {
    if (!args->all && args->view.view < 0)
      throw CLI::ValidationError("sim render", "give --view N or --all");
    if (!args->crop.empty())
      args->view.crop_px = cv::Rect(args->crop[0], args->crop[1], args->crop[2], args->crop[3]);
    if (args->all) {
      DispatchSummary(dispatch, [args]() -> Result<RenderSceneViewsSummary> {
        RenderSceneViewsOptions o = args->views;
        HR_ASSIGN_OR_RETURN(o.scene_file, SceneOrDefault(args->view.scene_file));
        o.out_dir = args->view.out_file;
        o.render.noise = args->view.noise;
        return RenderSceneViews(o);
      });
      return;
    }
    DispatchSummary(dispatch, [args]() -> Result<RenderViewFileSummary> {
      RenderViewFileOptions o = args->view;
      HR_ASSIGN_OR_RETURN(o.scene_file, SceneOrDefault(o.scene_file));
      return RenderViewFile(o);
    });
  });
}

}  // namespace

void AddSimCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* sim = app.add_subcommand("sim", "The simulated rig");
  sim->require_subcommand(1);
  AddRenderCommand(*sim, common, dispatch);
  AddServeCommand(*sim, common, dispatch);
  AddChArUcoCommand(*sim, common, dispatch);
}

}  // namespace hairrig
