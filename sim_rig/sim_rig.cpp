#include "sim_rig/sim_rig.h"

#include <filesystem>

#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/modbus_turntable.h"
#include "drivers/usb_relay.h"
#include "drivers/v4l2_camera.h"
#include "rig/capture.h"
#include "rig/rig_extension.h"
#include "rig/simulation_preview.h"
#include "sim_hw/capture_truth.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/renderer.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"
#include "sim_hw/sim_turntable_controller.h"
#include "sim_hw/sim_usb_relay.h"
#include "sim_hw/sim_v4l2.h"

namespace hairrig {

namespace fs = std::filesystem;

SimRigState::SimRigState() = default;
SimRigState::~SimRigState() = default;

namespace {

constexpr char kSection[] = "sim";
constexpr char kSimValue[] = "sim";  // the device field value that asks for a simulated peer

struct SimSection {
  std::string scene_path;  // resolved against the config's relative_to
  double time_scale = 0.01;
};

// Reads the `sim` section; errors are recorded in the config's document.
SimSection ReadSimSection(const RigConfig& config) {
  const ConfigNode sim = config.root.Child(kSection);
  sim.AllowOnlyKeys({"scene", "time_scale", "faults"});
  SimSection section;
  const std::string scene = sim.String("scene");
  section.time_scale = sim.Number("time_scale", 0.01, {.min = 1e-6, .max = 100});
  section.scene_path = scene.empty() || scene[0] == '/'
                           ? scene
                           : (fs::path(config.relative_to) / scene).lexically_normal().string();
  return section;
}

// The planned views as the ground truth lists them.
std::vector<PlannedTruthView> TruthViews(const CapturePlan& plan) {
  std::vector<PlannedTruthView> views;
  for (const PlannedView& v : plan.views) {
    views.push_back(
        {v.index, v.stop, v.camera_serial, plan.stops[static_cast<size_t>(v.stop)].angle_deg});
  }
  return views;
}

// Writes each capture's ground truth from the world's renders, each file
// through the capture folder's writer (its storage and storage.min_free_mb).
class GroundTruthWriter : public CaptureObserver {
 public:
  explicit GroundTruthWriter(std::shared_ptr<SimWorld> world) : world_(std::move(world)) {}

  Status OnCaptureBegin(const CapturePlan& plan, const CaptureFolder& folder) override {
    HR_ASSIGN_OR_RETURN(
        truth_, CaptureGroundTruth::Begin(*world_, TruthViews(plan), folder.dir, folder.write));
    return Status::Ok();
  }

  // A stopped capture's views without a frame get their maps when shot.
  Status OnCaptureEnd(const CaptureSummary& summary) override {
    if (!truth_) return Status::Ok();
    const std::unique_ptr<CaptureGroundTruth> truth = std::move(truth_);
    return truth->Finish(summary.missing_views);
  }

 private:
  std::shared_ptr<SimWorld> world_;
  std::unique_ptr<CaptureGroundTruth> truth_;
};

// The simulated peers of one rig's devices, served by its world.
class SimPeers {
 public:
  explicit SimPeers(SimRigState* state) : state_(state) {}

  // Points a modbus turntable whose host (TCP) or device (RTU) is "sim" at a
  // controller simulated by the world.
  Status ServeController(const DeviceConfig& config, ModbusTurntableOptions* options) const {
    ModbusEndpoint& e = options->endpoint;
    const bool tcp = e.transport == ModbusEndpoint::Transport::kTcp;
    if ((tcp ? e.host : e.device) != kSimValue) return Status::Ok();
    if (!state_->world) {
      return InvalidArgument(
          config.node.Where() + ": " + (tcp ? "host" : "device") +
          " 'sim' needs the rig config's sim section (the simulated world the controller drives)");
    }
    const SimTurntableController& controller = WorldTurntableController(*state_->world);
    const TurntableCapabilities caps = controller.capabilities();
    options->map.max_speed_deg_s = caps.max_speed_deg_s;
    options->map.max_accel_deg_s2 = caps.max_accel_deg_s2;
    options->map.settle_s = caps.settle_s;
    options->time_scale = controller.time_scale();
    const ModbusServerOptions server_options{options->map, config.serial, e.slave_id};
    auto server = tcp ? ModbusTurntableServer::StartTcp(state_->world, server_options)
                      : ModbusTurntableServer::StartRtu(state_->world, server_options);
    if (!server.ok()) return server.status();
    if (tcp) {
      e.host = (*server)->host();
      e.port = (*server)->port();
    } else {
      e.device = (*server)->device_path();
    }
    state_->modbus_servers.push_back(std::move(server).value());
    return Status::Ok();
  }

  // Points a gphoto2 camera whose port is "sim" at a simulated DSLR, rendering
  // the scene camera with the device's serial.
  Status ServeDslr(const DeviceConfig& config, Gphoto2CameraOptions* options) const {
    if (options->port != kSimValue) return Status::Ok();
    HR_ASSIGN_OR_RETURN(const int index, SceneCameraIndex(config, "port"));
    HR_RETURN_IF_ERROR(ExportSimDslrCamlibs());
    SimDslrOptions server_options;
    server_options.serial = config.serial;
    server_options.scene_camera = index;
    server_options.trigger_line = config.node.String("trigger_line", "");
    HR_ASSIGN_OR_RETURN(auto server, SimDslrServer::Start(state_->world, server_options));
    options->port = server->port();
    options->model = sim_dslr::kModel;
    options->nominal = SceneCameraNominal(index);
    state_->dslr_servers.push_back(std::move(server));
    return Status::Ok();
  }

  // Points an aravis camera whose address is "sim" at Aravis' in-process fake
  // camera, fed with the scene camera with the device's serial.
  Status ServeAravisCamera(const DeviceConfig& config, AravisCameraOptions* options) const {
    if (options->address != kSimValue) return Status::Ok();
    HR_ASSIGN_OR_RETURN(const int index, SceneCameraIndex(config, "address"));
    const SimAravisOptions feed_options{config.serial, index,
                                        config.node.String("trigger_line", "")};
    auto feed = std::make_unique<SimAravisFeed>(state_->world, feed_options);
    SimAravisFeed* raw = feed.get();
    options->connect = [raw, feed_options]() { return OpenSimAravisCamera(*raw, feed_options); };
    options->connect_name = "the simulated camera";
    options->address.clear();
    options->nominal = SceneCameraNominal(index);
    state_->aravis_feeds.push_back(std::move(feed));
    return Status::Ok();
  }

  // Points a v4l2 camera whose device is "sim" at a fake UVC camera showing
  // the scene camera with the device's serial, behind the backend's system-call layer.
  Status ServeUvcCamera(const DeviceConfig& config, V4l2CameraOptions* options) const {
    if (options->device != kSimValue) return Status::Ok();
    HR_ASSIGN_OR_RETURN(const int index, SceneCameraIndex(config, "device"));
    SimV4l2Options fake;
    fake.serial = config.serial;
    fake.scene_camera = index;
    options->io = std::make_shared<SimV4l2Device>(state_->world, fake);
    options->device = fake.node;
    options->nominal = SceneCameraNominal(index);
    return Status::Ok();
  }

  // Gives a usbrelay light with `bus: sim` a simulated board with its board
  // id (8 channels), its channel powering the scene light `light` (default:
  // the device's name).
  Status ServeRelay(const DeviceConfig& config, UsbRelayLightOptions* options) const {
    if (options->bus_name != kSimValue) {
      if (!config.node.Has("light")) return Status::Ok();
      config.node.Fail("light", "names a scene light: only with bus: sim");
      return config.node.status();
    }
    if (!state_->world) {
      return InvalidArgument(config.node.Where() +
                             ": bus 'sim' needs the rig config's sim section");
    }
    if (!state_->relay_bus) state_->relay_bus = std::make_shared<SimUsbRelayBus>(state_->world);
    // One board per id; each light adds its channel to the board's wiring.
    SimRelayBoard board{"sim-" + options->board_id, options->board_id, 8, {}};
    std::string light = config.node.String("light", "");
    if (light.empty()) light = config.name;
    if (!state_->relay_bus->HasBoard(board.board_id)) {
      HR_RETURN_IF_ERROR(state_->relay_bus->AddBoard(board));
    }
    HR_RETURN_IF_ERROR(state_->relay_bus->Wire(board.port_path, options->channel, light));
    options->bus = state_->relay_bus;
    return Status::Ok();
  }

 private:
  // The scene camera a simulated peer of device `config` renders: the one with its serial.
  Result<int> SceneCameraIndex(const DeviceConfig& config, const std::string& field) const {
    if (!state_->world) {
      return InvalidArgument(
          config.node.Where() + ": " + field +
          " 'sim' needs the rig config's sim section (the simulated world the camera renders)");
    }
    const Scene& scene = WorldRenderer(*state_->world).scene();
    const int index = scene.FindCamera(config.serial);
    if (index < 0) {
      return NotFound(config.node.Where() + ": the simulated scene (" + scene.path +
                      ") has no camera with serial '" + config.serial + "'");
    }
    return index;
  }

  // The simulated camera's size and timings, as a real unit's config gives them.
  CameraNominal SceneCameraNominal(int index) const {
    const Scene& scene = WorldRenderer(*state_->world).scene();
    const SceneCamera& camera = scene.cameras[static_cast<size_t>(index)];
    return {camera.intrinsics.width_px, camera.intrinsics.height_px, scene.camera_readout_s,
            scene.camera_download_s, WorldTimeScale(*state_->world)};
  }

  SimRigState* state_;
};

// Creates the world of a config with a `sim` section, with what hangs on it:
// the `sim` backends, the world's capture disk and the ground-truth writer.
Status CreateWorld(RigAssembly& assembly, SimRigState* state) {
  const RigConfig& config = assembly.config;
  const SimSection section = ReadSimSection(config);
  if (!config.root.ok()) return config.root.status();
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(section.scene_path));
  SimWorldOptions options;
  options.time_scale = section.time_scale;
  HR_ASSIGN_OR_RETURN(options.faults, ParseSimFaults(config.root.Child(kSection)));
  HR_ASSIGN_OR_RETURN(state->world, CreateSimWorld(scene, options));
  RegisterSimBackends(&assembly.registry, state->world);
  assembly.rig.capture_storage = MakeWorldCaptureStorage(*state->world);
  assembly.rig.capture_observers.push_back(std::make_shared<GroundTruthWriter>(state->world));
  return Status::Ok();
}

class SimRigExtension : public RigExtension {
 public:
  std::vector<std::string> ConfigSections() const override { return {kSection}; }

  Status CheckConfig(const RigConfig& config) const override {
    if (config.root.Has(kSection)) ReadSimSection(config);
    return config.root.status();
  }

  Status Attach(RigAssembly& assembly) const override {
    auto state = std::make_shared<SimRigState>();
    assembly.rig.extension_states.push_back(state);
    if (assembly.config.root.Has(kSection)) HR_RETURN_IF_ERROR(CreateWorld(assembly, state.get()));
    const SimPeers peers(state.get());
    RigBackendHooks& hooks = assembly.hooks;
    hooks.modbus.push_back([peers](const DeviceConfig& c, ModbusTurntableOptions* o) {
      return peers.ServeController(c, o);
    });
    hooks.gphoto2.push_back(
        [peers](const DeviceConfig& c, Gphoto2CameraOptions* o) { return peers.ServeDslr(c, o); });
    hooks.aravis.push_back([peers](const DeviceConfig& c, AravisCameraOptions* o) {
      return peers.ServeAravisCamera(c, o);
    });
    hooks.v4l2.push_back([peers](const DeviceConfig& c, V4l2CameraOptions* o) {
      return peers.ServeUvcCamera(c, o);
    });
    hooks.usb_relay.push_back(
        [peers](const DeviceConfig& c, UsbRelayLightOptions* o) { return peers.ServeRelay(c, o); });
    hooks.usb_relay_fields.push_back("light");
    return Status::Ok();
  }
};

// The scene's first camera at turntable angle 0, without sensor noise.
class SceneStrandPreviewer : public StrandPreviewer {
 public:
  explicit SceneStrandPreviewer(std::unique_ptr<Renderer> renderer)
      : renderer_(std::move(renderer)) {}
  Result<cv::Mat> Draw(const StrandSet& strands) override {
    renderer_->SetStrands(strands);
    RenderOptions options;
    options.noise = false;
    HR_ASSIGN_OR_RETURN(RenderedView view, renderer_->Render(0, 0.0, options));
    return view.image;
  }

 private:
  std::unique_ptr<Renderer> renderer_;
};

Result<std::unique_ptr<StrandPreviewer>> MakeSceneStrandPreviewer(const std::string& scene_file,
                                                                  const HeadSpec& head) {
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(scene_file));
  scene.head = head;
  scene.wig.num_strands = 1;  // replaced by the strands drawn
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, Renderer::Create(scene));
  return std::unique_ptr<StrandPreviewer>(
      std::make_unique<SceneStrandPreviewer>(std::move(renderer)));
}

}  // namespace

void RegisterSimRig() {
  static const bool registered = [] {
    RegisterRigExtension(std::make_shared<SimRigExtension>());
    RegisterStrandPreviewer(MakeSceneStrandPreviewer);
    return true;
  }();
  (void)registered;
}

const SimRigState* FindSimRigState(const Rig& rig) {
  for (const auto& state : rig.extension_states) {
    if (const auto* sim = dynamic_cast<const SimRigState*>(state.get())) return sim;
  }
  return nullptr;
}

}  // namespace hairrig
