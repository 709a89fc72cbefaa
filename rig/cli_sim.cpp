#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/charuco_board.h"
#include "core/file_util.h"
#include "core/parallel.h"
#include "rig/cli.h"
#include "rig/rig_config.h"
#include "sim_hw/charuco_views.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"
#include "sim_hw/view_set.h"

namespace hairrig {
namespace {

struct RenderArgs {
  std::string scene;
  std::string out;
  int view = -1;
  bool all = false;
  bool no_noise = false;
  int threads = 2;
  std::vector<int> crop;  // x, y, width, height (px); empty = the whole view
};

Result<std::unique_ptr<Renderer>> LoadRenderer(const std::string& scene_arg) {
  std::string path = scene_arg;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, EtcPath("scenes/default.yaml"));
  }
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(path));
  return Renderer::Create(scene);
}

Result<nlohmann::json> RenderOne(const RenderArgs& a) {
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, LoadRenderer(a.scene));
  const Scene& scene = renderer->scene();
  const int n = NumViews(scene);
  if (a.view < 0 || a.view >= n) {
    return InvalidArgument("--view " + std::to_string(a.view) + " is outside the plan's views 0-" + std::to_string(n - 1));
  }
  const std::string ext = FileExtension(a.out);
  if (ext != "png" && ext != "tif" && ext != "tiff" && ext != "jpg") {
    return InvalidArgument("--out " + a.out + ": give an image file name ending in .png, .tif or .jpg");
  }
  ViewGroundTruth g = MakeViewGroundTruth(scene, a.view);
  RenderOptions o;
  o.noise = !a.no_noise;
  o.noise_seed = scene.seed * 1000003ull + static_cast<uint64_t>(a.view);
  HR_ASSIGN_OR_RETURN(RenderedView view, renderer->Render(g.camera_index, g.turntable_deg, o));
  if (!a.crop.empty()) {
    const cv::Rect rect(a.crop[0], a.crop[1], a.crop[2], a.crop[3]);
    if (rect.width <= 0 || rect.height <= 0 || (rect & cv::Rect(0, 0, view.image.cols, view.image.rows)) != rect) {
      return InvalidArgument("--crop " + std::to_string(rect.x) + "," + std::to_string(rect.y) + "," +
                             std::to_string(rect.width) + "," + std::to_string(rect.height) + " is not inside the " +
                             std::to_string(view.image.cols) + " x " + std::to_string(view.image.rows) + " view");
    }
    view.image = view.image(rect).clone();
  }
  std::vector<uint8_t> bytes;
  if (!cv::imencode("." + ext, view.image, bytes)) return IoError(a.out + ": encoding failed");
  HR_RETURN_IF_ERROR(WriteFileAtomic(a.out, bytes.data(), bytes.size()));
  g.tags = view.tags;
  int visible = 0;
  for (const TagTruth& t : view.tags) visible += t.unoccluded ? 1 : 0;
  return nlohmann::json{{"view", a.view},          {"camera_serial", g.camera_serial}, {"turntable_deg", g.turntable_deg},
                        {"out", a.out},            {"width_px", view.image.cols},      {"height_px", view.image.rows},
                        {"tags_unoccluded", visible}};
}

Result<nlohmann::json> RenderAll(const RenderArgs& a) {
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, LoadRenderer(a.scene));
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) return IoError(a.out + ": cannot create the output folder (" + ec.message() + ")");
  RenderViewsOptions o;
  o.threads = a.threads;
  o.noise = !a.no_noise;
  HR_ASSIGN_OR_RETURN(RenderViewsSummary s, RenderAllViews(*renderer, a.out, o));
  return nlohmann::json{{"views", s.views},
                        {"out", a.out},
                        {"contact_sheet", a.out + "/" + s.contact_sheet},
                        {"ground_truth", a.out + "/" + s.ground_truth},
                        {"strands", renderer->strands_turntable_mm().num_strands()},
                        {"wall_s", s.wall_s},
                        {"seconds_per_view", s.wall_s / std::max(1, s.views)}};
}

struct ChArUcoArgs {
  std::string scene;
  std::string board;
  std::string out;
  std::vector<std::string> serials;  // empty: every camera of the scene
  int views = 25;
  uint64_t seed = 1;
  int threads = 2;
};

// One folder per camera of what a technician records for calibrate-intrinsics.
Result<nlohmann::json> RenderChArUco(const ChArUcoArgs& a) {
  std::string scene_path = a.scene, board_path = a.board;
  if (scene_path.empty()) {
    HR_ASSIGN_OR_RETURN(scene_path, EtcPath("scenes/default.yaml"));
  }
  if (board_path.empty()) {
    HR_ASSIGN_OR_RETURN(board_path, EtcPath("charuco-board.yaml"));
  }
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(scene_path));
  HR_ASSIGN_OR_RETURN(ChArUcoBoard board, LoadChArUcoBoard(board_path));
  std::vector<int> cameras;
  for (const std::string& serial : a.serials) {
    const int index = scene.FindCamera(serial);
    if (index < 0) return NotFound("--camera " + serial + " is not a camera of " + scene_path);
    cameras.push_back(index);
  }
  if (cameras.empty())
    for (size_t c = 0; c < scene.cameras.size(); ++c) cameras.push_back(static_cast<int>(c));
  std::vector<Result<ChArUcoSetSummary>> sets(cameras.size(), Internal("not rendered"));
  ParallelFor(cameras.size(), a.threads, [&] {
    return [&](size_t i) {
      const SceneCamera& camera = scene.cameras[static_cast<size_t>(cameras[i])];
      sets[i] = WriteChArUcoSet(scene, cameras[i], board, a.views, a.seed + static_cast<uint64_t>(cameras[i]),
                                (std::filesystem::path(a.out) / camera.serial).string());
    };
  });
  nlohmann::json out{{"out", a.out}, {"board", board_path}, {"cameras", nlohmann::json::array()}};
  for (size_t i = 0; i < cameras.size(); ++i) {
    HR_RETURN_IF_ERROR(sets[i].status());
    out["cameras"].push_back({{"serial", scene.cameras[static_cast<size_t>(cameras[i])].serial},
                              {"dir", sets[i]->dir},
                              {"images", sets[i]->images.size()},
                              {"ground_truth", sets[i]->ground_truth}});
  }
  return out;
}

void AddChArUcoCommand(CLI::App& sim, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = sim.add_subcommand("charuco", "Render what a technician records to calibrate each camera's intrinsics "
                                            "alone: a ChArUco board held in front of it (OUT/<serial>/)");
  auto args = std::make_shared<ChArUcoArgs>();
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_option("--scene", args->scene, "scene file (default: etc/scenes/default.yaml)");
  cmd->add_option("--board", args->board, "ChArUco board file (default: etc/charuco-board.yaml)");
  cmd->add_option("--camera", args->serials, "only this camera (serial); repeat for several");
  cmd->add_option("--views", args->views, "images per camera")->check(CLI::Range(1, 500))->capture_default_str();
  cmd->add_option("--seed", args->seed, "board poses and sensor noise")->capture_default_str();
  cmd->add_option("--threads", args->threads, "cameras rendered at once")->check(CLI::Range(1, 64));
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RenderChArUco(*args); };
    dispatch.print_human = [](const nlohmann::json& j) {
      for (const auto& c : j["cameras"])
        std::printf("%s: %d images of the board in %s (ground truth: %s)\n  calibrate: hairrig calibrate-intrinsics %s "
                    "--board %s --serial %s\n",
                    c["serial"].get<std::string>().c_str(), c["images"].get<int>(), c["dir"].get<std::string>().c_str(),
                    c["ground_truth"].get<std::string>().c_str(), c["dir"].get<std::string>().c_str(),
                    j["board"].get<std::string>().c_str(), c["serial"].get<std::string>().c_str());
    };
  });
}

struct ServeArgs {
  std::string scene;
  std::string serial = "SIM-TT-0001";
  int modbus_port = 0;
  int slave_id = 1;
  double time_scale = 1.0;
  bool rtu = true;
  bool dslr = true;
  bool gige = true;
};

// How an outside tool reaches each simulator, printed when they are up.
void PrintEndpoints(const ModbusTurntableServer& tcp, const ModbusTurntableServer* rtu, const ServeArgs& a) {
  std::printf("simulated turntable controller %s (register map: etc/rig-example.yaml)\n", a.serial.c_str());
  std::printf("  %s\n    try: mbpoll -m tcp -p %d -a %d -0 -1 -t 4:int -B -r 10 127.0.0.1   (position, counts)\n",
              tcp.Describe().c_str(), tcp.port(), a.slave_id);
  if (rtu != nullptr) {
    std::printf("  %s\n    try: mbpoll -m rtu -b 115200 -P none -a %d -0 -1 -t 4 -r 1 %s   (status bits)\n",
                rtu->Describe().c_str(), a.slave_id, rtu->device_path().c_str());
  }
}

void PrintGigE(const SimGigECamera* gige) {
  if (gige == nullptr) return;
  std::printf("simulated GigE Vision camera (Aravis' fake, rendering the view)\n  %s\n"
              "    try: arv-tool-0.8 -a %s control DeviceSerialNumber Width Height PixelFormat\n",
              gige->Describe().c_str(), gige->address().c_str());
}

void PrintDslrs(const std::vector<std::unique_ptr<SimDslrServer>>& dslrs, const std::string& camlibs) {
  if (dslrs.empty()) return;
  std::printf("simulated DSLRs (libgphoto2 camlib in %s)\n  export CAMLIBS=%s\n", camlibs.c_str(), camlibs.c_str());
  for (const auto& d : dslrs) {
    std::printf("  %s\n    try: gphoto2 --camera '%s' --port %s --capture-image-and-download\n",
                d->Describe().c_str(), sim_dslr::kModel, d->port().c_str());
  }
}

// Runs the protocol-level simulators until SIGINT or SIGTERM.
Result<nlohmann::json> Serve(const ServeArgs& a) {
  std::string path = a.scene;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, EtcPath("scenes/default.yaml"));
  }
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(path));
  SimWorldOptions world_options;
  world_options.time_scale = a.time_scale;
  HR_ASSIGN_OR_RETURN(std::shared_ptr<SimWorld> world, CreateSimWorld(scene, world_options));
  // Blocked before the servers' threads start, so that only sigwait sees them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  const ModbusServerOptions modbus{ModbusRegisterMap{}, a.serial, a.slave_id};
  HR_ASSIGN_OR_RETURN(auto tcp, ModbusTurntableServer::StartTcp(world, modbus, "127.0.0.1", a.modbus_port));
  std::unique_ptr<ModbusTurntableServer> rtu;
  if (a.rtu) {
    HR_ASSIGN_OR_RETURN(rtu, ModbusTurntableServer::StartRtu(world, modbus));
  }
  // One simulated DSLR per scene camera, rendering that camera's view.
  std::vector<std::unique_ptr<SimDslrServer>> dslrs;
  std::string camlibs;
  if (a.dslr) {
    HR_ASSIGN_OR_RETURN(camlibs, SimDslrCamlibFolder());
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
      SimDslrOptions options;
      options.serial = scene.cameras[i].serial;
      options.scene_camera = static_cast<int>(i);
      HR_ASSIGN_OR_RETURN(auto server, SimDslrServer::Start(world, options));
      dslrs.push_back(std::move(server));
    }
  }
  // The GigE fake takes 127.0.0.1:3956, so only one camera: the scene's last.
  std::unique_ptr<SimGigECamera> gige;
  if (a.gige && !scene.cameras.empty()) {
    const int index = static_cast<int>(scene.cameras.size()) - 1;
    HR_ASSIGN_OR_RETURN(gige, SimGigECamera::Start(world, {scene.cameras.back().serial, index, "", true}));
  }
  PrintEndpoints(*tcp, rtu.get(), a);
  PrintDslrs(dslrs, camlibs);
  PrintGigE(gige.get());
  std::printf("Ctrl-C stops.\n");
  std::fflush(stdout);
  int signal = 0;
  sigwait(&stop_signals, &signal);
  tcp->Stop();
  if (rtu) rtu->Stop();
  nlohmann::json gige_summary = nullptr;
  if (gige) {
    gige_summary = {{"serial", gige->serial()}, {"address", gige->address()}, {"frames", gige->frames_rendered()}};
    gige.reset();
  }
  nlohmann::json cameras = nlohmann::json::array();
  for (const auto& d : dslrs) {
    d->Stop();
    cameras.push_back({{"serial", d->serial()}, {"port", d->port()}, {"shots", d->shots()}});
  }
  pthread_sigmask(SIG_UNBLOCK, &stop_signals, nullptr);
  nlohmann::json servers = nlohmann::json::array();
  for (const ModbusTurntableServer* s : {tcp.get(), rtu.get()}) {
    if (s != nullptr) servers.push_back({{"endpoint", s->Describe()}, {"requests_served", s->requests_served()}});
  }
  return nlohmann::json{
      {"stopped_by", signal == SIGINT ? "SIGINT" : "SIGTERM"}, {"modbus", servers}, {"dslr", cameras},
      {"gige", gige_summary}};
}

void AddServeCommand(CLI::App& sim, CommonOptions& common, Dispatch& dispatch) {
  auto* serve = sim.add_subcommand("serve", "Run the protocol-level simulators for outside tools until Ctrl-C");
  auto args = std::make_shared<ServeArgs>();
  serve->add_option("--scene", args->scene, "scene file (default: etc/scenes/default.yaml)");
  serve->add_option("--serial", args->serial, "the simulated turntable controller's serial number");
  serve->add_option("--modbus-port", args->modbus_port, "Modbus TCP port on 127.0.0.1 (default: a free one)")
      ->check(CLI::Range(0, 65535));
  serve->add_option("--slave-id", args->slave_id, "Modbus unit id")->check(CLI::Range(1, 247));
  serve->add_option("--time-scale", args->time_scale, "device seconds x this = wall seconds (default 1: real time)")
      ->check(CLI::PositiveNumber);
  serve->add_flag("!--no-rtu", args->rtu, "do not serve Modbus RTU on a pseudo-terminal");
  serve->add_flag("!--no-dslr", args->dslr, "do not serve the simulated DSLRs (one per scene camera)");
  serve->add_flag("!--no-gige", args->gige,
                  "do not serve the simulated GigE Vision camera (the scene's last camera, on 127.0.0.1:3956)");
  serve->add_flag("--json", common.json, "print the closing summary as one JSON object");
  serve->callback([args, &dispatch] {
    dispatch.action = [args]() { return Serve(*args); };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("stopped (%s)\n", j["stopped_by"].get<std::string>().c_str());
      for (const auto& s : j["modbus"]) {
        std::printf("  %s: %ld requests served\n", s["endpoint"].get<std::string>().c_str(),
                    s["requests_served"].get<long>());
      }
      if (!j["gige"].is_null()) {
        std::printf("  simulated GigE Vision camera %s at %s: %d frames\n", j["gige"]["serial"].get<std::string>().c_str(),
                    j["gige"]["address"].get<std::string>().c_str(), j["gige"]["frames"].get<int>());
      }
      for (const auto& d : j["dslr"]) {
        std::printf("  simulated DSLR %s at %s: %d shots\n", d["serial"].get<std::string>().c_str(),
                    d["port"].get<std::string>().c_str(), d["shots"].get<int>());
      }
    };
  });
}

}  // namespace

void AddSimCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* sim = app.add_subcommand("sim", "The simulated rig");
  sim->require_subcommand(1);
  auto* render = sim->add_subcommand("render", "Render one view (--view N --out FILE) or all (--all --out DIR)");
  auto args = std::make_shared<RenderArgs>();
  render->add_option("--scene", args->scene, "scene file (default: etc/scenes/default.yaml)");
  auto* view = render->add_option("--view", args->view, "view index: stop * cameras + camera");
  auto* all = render->add_flag("--all", args->all, "every view, a contact sheet and the ground truth");
  view->excludes(all);
  render->add_option("--out", args->out, "output image (--view) or folder (--all)")->required();
  render->add_flag("--no-noise", args->no_noise, "render without sensor noise");
  render->add_option("--crop", args->crop, "with --view: write only the pixels X,Y,WIDTH,HEIGHT, at full resolution")
      ->delimiter(',')
      ->expected(4)
      ->excludes(all);
  render->add_option("--threads", args->threads, "render threads for --all")->check(CLI::Range(1, 64));
  render->add_flag("--json", common.json, "print the summary as one JSON object");
  AddServeCommand(*sim, common, dispatch);
  AddChArUcoCommand(*sim, common, dispatch);
  render->callback([args, &dispatch] {
    if (!args->all && args->view < 0) throw CLI::ValidationError("sim render", "give --view N or --all");
    dispatch.action = [args]() { return args->all ? RenderAll(*args) : RenderOne(*args); };
    dispatch.print_human = [args](const nlohmann::json& j) {
      if (args->all) {
        std::printf("rendered %d views in %.1f s (%.2f s per view) to %s\ncontact sheet: %s\nground truth: %s\n",
                    j["views"].get<int>(), j["wall_s"].get<double>(), j["seconds_per_view"].get<double>(),
                    j["out"].get<std::string>().c_str(), j["contact_sheet"].get<std::string>().c_str(),
                    j["ground_truth"].get<std::string>().c_str());
      } else {
        std::printf("view %d (%s, turntable %.2f deg) -> %s\n", j["view"].get<int>(),
                    j["camera_serial"].get<std::string>().c_str(), j["turntable_deg"].get<double>(),
                    j["out"].get<std::string>().c_str());
      }
    };
  });
}

}  // namespace hairrig
