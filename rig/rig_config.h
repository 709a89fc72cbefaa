// The rig config (etc/sim-rig.yaml and its kin) and the devices built from it.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "core/capture_storage.h"
#include "core/config.h"
#include "core/head_spec.h"
#include "drivers/registry.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_dslr_server.h"
#include "sim_hw/sim_usb_relay.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {

struct RigConfig {
  std::string path;
  std::string relative_to;     // folder relative paths resolve against
  std::string name;
  std::string sim_scene_path;  // resolved; empty when no sim section
  double sim_time_scale = 0.01;
  // The subject's head as the lab knows it (its `head:` section: a mannequin's
  // mesh and pose, or an ellipsoid, with the scalp region); absent when the
  // config has none.
  std::optional<HeadSpec> head;
  ConfigNode root;             // the whole document
};

// Finds etc/sim-rig.yaml: $HAIRRIG_ETC, then the etc/ of the source tree this
// binary was built from, then ./etc. NotFound names the places tried.
Result<std::string> DefaultRigConfigPath();
// Resolves a path given relative to the project's etc/ folder ("scenes/default.yaml").
Result<std::string> EtcPath(const std::string& relative);

// Relative paths in the config (sim.scene) resolve against `relative_to`, by
// default the config file's folder (a capture's snapshot passes the folder of
// the config it was taken from).
Result<RigConfig> LoadRigConfig(const std::string& path, const std::string& relative_to = "");

struct Rig {
  RigConfig config;
  std::shared_ptr<SimWorld> sim_world;  // set when the config has a sim section
  // The disk captures with this rig are written to, when the rig brings its
  // own: the simulated rig's with a `disk_full` fault. Null: the file system.
  std::shared_ptr<CaptureStorage> capture_storage;
  // Protocol-level simulators this rig talks to (declared before `devices`,
  // so they outlive the devices connected to them).
  std::vector<std::unique_ptr<ModbusTurntableServer>> sim_modbus_servers;
  std::vector<std::unique_ptr<SimDslrServer>> sim_dslr_servers;
  std::vector<std::unique_ptr<SimAravisFeed>> sim_aravis_feeds;
  std::shared_ptr<SimUsbRelayBus> sim_relay_bus;  // the boards of `usbrelay` lights with bus: sim
  DeviceSet devices;
  // Camera name -> the trigger line it is wired to (devices.cameras[].trigger_line);
  // cameras without one are triggered in software.
  std::map<std::string, std::string> camera_trigger_lines;
};

struct RigBuildOptions {
  // Registers further backends (the replay backend) before devices are built.
  std::function<void(DeviceRegistry*)> register_backends;
  std::string backend_override;  // build every device with this backend
  bool simulate = true;          // create the sim world when the config has a `sim` section
  // Called with the built rig (devices closed, simulated peers serving), for
  // observers such as a test that reaches a simulated peer.
  std::function<void(const Rig&)> on_built;
};

// Builds every device (closed). The sim backend is available when the config
// has a `sim` section; so is a simulated peer for the real backends: a
// `modbus` turntable with `host: sim` (TCP) or `device: sim` (RTU) talks to a
// simulated controller this rig serves on loopback or a pseudo-terminal, and a
// `gphoto2` camera with `port: sim` is a simulated DSLR (sim_hw/sim_dslr_server.h)
// rendering the scene camera with its serial, reached through the project's
// camlib (CAMLIBS is set for this process), and an `aravis` camera with
// `address: sim` is Aravis' in-process fake camera rendering that scene
// camera, a `v4l2` camera with `device: sim` a fake UVC camera behind the
// backend's system-call layer (sim_hw/sim_v4l2.h), and a `usbrelay` light with
// `bus: sim` a channel of a simulated relay board powering its scene light.
Result<std::unique_ptr<Rig>> BuildRig(const RigConfig& config, const RigBuildOptions& options = {});

}  // namespace hairrig
