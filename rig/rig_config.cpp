#include "rig/rig_config.h"

#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/gpio_devices.h"
#include "drivers/usb_relay.h"
#include "drivers/v4l2_camera.h"
#include "drivers/modbus_turntable.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"
#include "sim_hw/sim_turntable_controller.h"
#include "sim_hw/sim_v4l2.h"

#include "core/head_config.h"

#include <cstdlib>
#include <filesystem>

namespace hairrig {

namespace fs = std::filesystem;

Result<std::string> EtcPath(const std::string& relative) {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("HAIRRIG_ETC")) candidates.emplace_back(env);
  candidates.emplace_back(fs::path(HAIRRIG_SOURCE_DIR) / "etc");
  candidates.emplace_back(fs::current_path() / "etc");
  std::string tried;
  for (const auto& dir : candidates) {
    const fs::path p = dir / relative;
    if (fs::exists(p)) return p.lexically_normal().string();
    tried += (tried.empty() ? "" : ", ") + p.string();
  }
  return NotFound("cannot find " + relative + " (tried " + tried + "); set HAIRRIG_ETC to the project's etc/ folder");
}

Result<std::string> DefaultRigConfigPath() { return EtcPath("sim-rig.yaml"); }

Result<RigConfig> LoadRigConfig(const std::string& path, const std::string& relative_to) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  root.AllowOnlyKeys({"name", "sim", "devices", "plan", "storage", "retries", "calibration", "head"});
  RigConfig config;
  config.path = path;
  config.relative_to = relative_to.empty() ? fs::absolute(path).parent_path().string() : relative_to;
  config.root = root;
  config.name = root.String("name", fs::path(path).stem().string());
  if (root.Has("sim")) {
    const ConfigNode sim = root.Child("sim");
    sim.AllowOnlyKeys({"scene", "time_scale", "faults"});
    const std::string scene = sim.String("scene");
    config.sim_time_scale = sim.Number("time_scale", 0.01, {.min = 1e-6, .max = 100});
    if (!scene.empty() && scene[0] != '/') {
      config.sim_scene_path = (fs::path(config.relative_to) / scene).lexically_normal().string();
    } else {
      config.sim_scene_path = scene;
    }
  }
  if (root.Has("head")) {
    config.head.emplace();
    // ReadHeadConfig resolves relative paths beside a file: one inside relative_to.
    HR_RETURN_IF_ERROR(ReadHeadConfig(root, "head", (fs::path(config.relative_to) / "rig.yaml").string(),
                                      &*config.head));
  }
  root.Child("devices");
  if (!root.ok()) return root.status();
  return config;
}

namespace {

// Points a modbus turntable whose host (TCP) or device (RTU) is "sim" at a
// controller simulated by this rig's world.
Status ServeSimulatedController(Rig* rig, const DeviceConfig& config, ModbusTurntableOptions* options) {
  ModbusEndpoint& e = options->endpoint;
  const bool tcp = e.transport == ModbusEndpoint::Transport::kTcp;
  if ((tcp ? e.host : e.device) != "sim") return Status::Ok();
  if (!rig->sim_world) {
    return InvalidArgument(config.node.Where() + ": " + (tcp ? "host" : "device") +
                           " 'sim' needs the rig config's sim section (the simulated world the controller drives)");
  }
  const SimTurntableController& controller = WorldTurntableController(*rig->sim_world);
  const TurntableCapabilities caps = controller.capabilities();
  options->map.max_speed_deg_s = caps.max_speed_deg_s;
  options->map.max_accel_deg_s2 = caps.max_accel_deg_s2;
  options->map.settle_s = caps.settle_s;
  options->time_scale = controller.time_scale();
  const ModbusServerOptions server_options{options->map, config.serial, e.slave_id};
  auto server = tcp ? ModbusTurntableServer::StartTcp(rig->sim_world, server_options)
                    : ModbusTurntableServer::StartRtu(rig->sim_world, server_options);
  if (!server.ok()) return server.status();
  if (tcp) {
    e.host = (*server)->host();
    e.port = (*server)->port();
  } else {
    e.device = (*server)->device_path();
  }
  rig->sim_modbus_servers.push_back(std::move(server).value());
  return Status::Ok();
}

// The scene camera a simulated peer of device `config` renders: the one with its serial.
Result<int> SimSceneCamera(const Rig& rig, const DeviceConfig& config, const std::string& field) {
  if (!rig.sim_world) {
    return InvalidArgument(config.node.Where() + ": " + field +
                           " 'sim' needs the rig config's sim section (the simulated world the camera renders)");
  }
  const Scene& scene = WorldRenderer(*rig.sim_world).scene();
  const int index = scene.FindCamera(config.serial);
  if (index < 0) {
    return NotFound(config.node.Where() + ": the simulated scene (" + scene.path + ") has no camera with serial '" +
                    config.serial + "'");
  }
  return index;
}

// The simulated camera's size and timings, as a real unit's config gives them.
CameraNominal SceneCameraNominal(const SimWorld& world, int index) {
  const Scene& scene = WorldRenderer(world).scene();
  const SceneCamera& camera = scene.cameras[static_cast<size_t>(index)];
  return {camera.intrinsics.width_px, camera.intrinsics.height_px, scene.camera_readout_s, scene.camera_download_s,
          WorldTimeScale(world)};
}

// Points a gphoto2 camera whose port is "sim" at a simulated DSLR this rig
// serves, rendering the scene camera with the device's serial.
Status ServeSimulatedDslr(Rig* rig, const DeviceConfig& config, Gphoto2CameraOptions* options) {
  if (options->port != "sim") return Status::Ok();
  HR_ASSIGN_OR_RETURN(const int index, SimSceneCamera(*rig, config, "port"));
  HR_RETURN_IF_ERROR(ExportSimDslrCamlibs());
  SimDslrOptions server_options;
  server_options.serial = config.serial;
  server_options.scene_camera = index;
  server_options.trigger_line = config.node.String("trigger_line", "");
  HR_ASSIGN_OR_RETURN(auto server, SimDslrServer::Start(rig->sim_world, server_options));
  options->port = server->port();
  options->model = sim_dslr::kModel;
  options->nominal = SceneCameraNominal(*rig->sim_world, index);
  rig->sim_dslr_servers.push_back(std::move(server));
  return Status::Ok();
}

// Points an aravis camera whose address is "sim" at Aravis' in-process fake
// camera, fed with the scene camera with the device's serial.
Status ServeSimulatedAravisCamera(Rig* rig, const DeviceConfig& config, AravisCameraOptions* options) {
  if (options->address != "sim") return Status::Ok();
  HR_ASSIGN_OR_RETURN(const int index, SimSceneCamera(*rig, config, "address"));
  const SimAravisOptions feed_options{config.serial, index, config.node.String("trigger_line", "")};
  auto feed = std::make_unique<SimAravisFeed>(rig->sim_world, feed_options);
  SimAravisFeed* raw = feed.get();
  options->connect = [raw, feed_options]() { return OpenSimAravisCamera(*raw, feed_options); };
  options->address.clear();
  options->nominal = SceneCameraNominal(*rig->sim_world, index);
  rig->sim_aravis_feeds.push_back(std::move(feed));
  return Status::Ok();
}

// Points a v4l2 camera whose device is "sim" at a fake UVC camera showing
// the scene camera with the device's serial, behind the backend's system-call layer.
Status ServeSimulatedUvcCamera(Rig* rig, const DeviceConfig& config, V4l2CameraOptions* options) {
  if (options->device != "sim") return Status::Ok();
  HR_ASSIGN_OR_RETURN(const int index, SimSceneCamera(*rig, config, "device"));
  SimV4l2Options fake;
  fake.serial = config.serial;
  fake.scene_camera = index;
  options->io = std::make_shared<SimV4l2Device>(rig->sim_world, fake);
  options->device = fake.node;
  options->nominal = SceneCameraNominal(*rig->sim_world, index);
  return Status::Ok();
}

// Gives a usbrelay light with `bus: sim` a simulated board with its board
// id (8 channels), its channel powering the scene light `light` (default: the device's name).
Status ServeSimulatedRelay(Rig* rig, const DeviceConfig& config, UsbRelayLightOptions* options) {
  if (!options->simulated) return Status::Ok();
  if (!rig->sim_world) return Status::Ok();  // the backend names the missing sim section
  if (!rig->sim_relay_bus) rig->sim_relay_bus = std::make_shared<SimUsbRelayBus>(rig->sim_world);
  // One board per id; each light adds its channel to the board's wiring.
  SimRelayBoard board{"sim-" + options->board_id, options->board_id, 8, {}};
  const std::string light = options->sim_light.empty() ? config.name : options->sim_light;
  if (!rig->sim_relay_bus->HasBoard(board.board_id)) HR_RETURN_IF_ERROR(rig->sim_relay_bus->AddBoard(board));
  HR_RETURN_IF_ERROR(rig->sim_relay_bus->Wire(board.port_path, options->channel, light));
  options->bus = rig->sim_relay_bus;
  return Status::Ok();
}

}  // namespace

Result<std::unique_ptr<Rig>> BuildRig(const RigConfig& config, const RigBuildOptions& build) {
  auto rig = std::make_unique<Rig>();
  rig->config = config;
  DeviceRegistry registry;
  if (build.register_backends) build.register_backends(&registry);
  RegisterGpioBackends(&registry, MakeLibgpiodProvider());
  Rig* raw = rig.get();
  RegisterModbusTurntableBackend(&registry, [raw](const DeviceConfig& c, ModbusTurntableOptions* options) {
    return ServeSimulatedController(raw, c, options);
  });
  RegisterGphoto2Backend(&registry, [raw](const DeviceConfig& c, Gphoto2CameraOptions* options) {
    return ServeSimulatedDslr(raw, c, options);
  });
  RegisterAravisBackend(&registry, [raw](const DeviceConfig& c, AravisCameraOptions* options) {
    return ServeSimulatedAravisCamera(raw, c, options);
  });
  RegisterV4l2Backend(&registry, [raw](const DeviceConfig& c, V4l2CameraOptions* options) {
    return ServeSimulatedUvcCamera(raw, c, options);
  });
  RegisterUsbRelayBackend(&registry, [raw](const DeviceConfig& c, UsbRelayLightOptions* options) {
    return ServeSimulatedRelay(raw, c, options);
  });
  if (build.simulate && !config.sim_scene_path.empty()) {
    HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(config.sim_scene_path));
    SimWorldOptions options;
    options.time_scale = config.sim_time_scale;
    HR_ASSIGN_OR_RETURN(options.faults, ParseSimFaults(config.root.Child("sim")));
    HR_ASSIGN_OR_RETURN(rig->sim_world, CreateSimWorld(scene, options));
    RegisterSimBackends(&registry, rig->sim_world);
    rig->capture_storage = MakeWorldCaptureStorage(*rig->sim_world);
  }
  HR_ASSIGN_OR_RETURN(rig->devices, BuildDevices(config.root.Child("devices"), registry, build.backend_override));
  for (const ConfigNode& camera : config.root.Child("devices").Items("cameras")) {
    const std::string line = camera.String("trigger_line", "");
    if (line.empty()) continue;
    bool known = false;
    for (const auto& l : rig->devices.trigger_lines) known = known || l->info().name == line;
    if (!known) camera.Fail("trigger_line", "no trigger line named '" + line + "' in devices.trigger_lines");
    rig->camera_trigger_lines[camera.String("name")] = line;
  }
  if (!config.root.ok()) return config.root.status();
  if (build.on_built) build.on_built(*rig);
  return rig;
}

}  // namespace hairrig
