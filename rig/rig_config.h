// The rig config (etc/sim-rig.yaml and its kin) and the devices built from it.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/capture_storage.h"
#include "core/config.h"
#include "core/head_spec.h"
#include "drivers/registry.h"

namespace hairrig {

// The sections a rig extension reads (rig/rig_extension.h: the simulated
// rig's `sim`) are in `root`; the extension checks them when the config is loaded.
struct RigConfig {
  std::string path;
  std::string relative_to;  // folder relative paths resolve against
  std::string name;
  // The subject's head as the lab knows it (its `head:` section: a mannequin's
  // mesh and pose, or an ellipsoid, with the scalp region); absent when the
  // config has none.
  std::optional<HeadSpec> head;
  ConfigNode root;  // the whole document
};

// Finds etc/sim-rig.yaml: $HAIRRIG_ETC, then the etc/ of the source tree this
// binary was built from, then ./etc. NotFound names the places tried.
Result<std::string> DefaultRigConfigPath();
// Resolves a path given relative to the project's etc/ folder ("scenes/default.yaml").
Result<std::string> EtcPath(const std::string& relative);

// Top-level sections of a config that no registered rig extension reads
// (rig/rig_extension.h): refused as unknown fields (a typo), or ignored by
// readers of a recorded capture's snapshot, which was checked when it was
// captured, perhaps by a process with other extensions.
enum class UnclaimedSections { kRefuse, kIgnore };

// Relative paths in the config (head, an extension's files such as sim.scene)
// resolve against `relative_to`, by default the config file's folder (a
// capture's snapshot passes the folder of the config it was taken from).
// Every registered rig extension checks its sections.
Result<RigConfig> LoadRigConfig(const std::string& path, const std::string& relative_to = "",
                                UnclaimedSections unclaimed = UnclaimedSections::kRefuse);

// What a rig extension (rig/rig_extension.h) keeps for one rig: the peers it
// serves, the world they share. Extensions derive their own state from it.
class RigExtensionState {
 public:
  virtual ~RigExtensionState() = default;
};

class CaptureObserver;  // rig/capture.h

struct Rig {
  RigConfig config;
  // What the rig extensions started for this rig (declared before `devices`,
  // so it outlives the devices connected to it).
  std::vector<std::shared_ptr<RigExtensionState>> extension_states;
  // The disk captures with this rig are written to, when the rig brings its
  // own (an extension's: the simulated rig's with a `disk_full` fault). Null:
  // the file system.
  std::shared_ptr<CaptureStorage> capture_storage;
  DeviceSet devices;
  // Camera name -> the trigger line it is wired to (devices.cameras[].trigger_line);
  // cameras without one are triggered in software.
  std::map<std::string, std::string> camera_trigger_lines;
  // Told when each capture with this rig begins and ends (RunCapture, in this
  // order); extensions add theirs (the simulated rig's writes the ground truth).
  std::vector<std::shared_ptr<CaptureObserver>> capture_observers;
};

struct RigBuildOptions {
  // Registers further backends (the replay backend) before devices are built.
  std::function<void(DeviceRegistry*)> register_backends;
  std::string backend_override;  // build every device with this backend
  // Attach the registered rig extensions (false: a replay, whose backend
  // stands in for every device, starts no simulated peer).
  bool attach_extensions = true;
  // Called with the built rig (devices closed, extensions' peers serving), for
  // observers such as a test that reaches a simulated peer.
  std::function<void(const Rig&)> on_built;

  // Every value is valid: an unknown backend_override is refused by the
  // device registry, naming the device.
  Status Check() const { return Status::Ok(); }
};

// Builds every device (closed) with the real backends (modbus, gphoto2,
// aravis, v4l2, gpiod, usbrelay), those of `options.register_backends`, and
// what the registered rig extensions add: their own backends (the simulated
// rig's `sim`) and hooks that rewrite a real backend's options before its
// device is built (the simulated rig points `host: sim`, `port: sim`,
// `address: sim`, `device: sim` and `bus: sim` at simulated peers it serves:
// sim_rig/sim_rig.h). Errors name the file, line and field.
Result<std::unique_ptr<Rig>> BuildRig(const RigConfig& config, const RigBuildOptions& options = {});

}  // namespace hairrig
