// The rig config (etc/rig.yaml and its kin) and the devices built from it.
#pragma once

#include <memory>
#include <string>

#include "core/config.h"
#include "drivers/registry.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {

struct RigConfig {
  std::string path;
  std::string name;
  std::string sim_scene_path;  // resolved; empty when no sim section
  double sim_time_scale = 0.01;
  ConfigNode root;             // the whole document
};

// Finds etc/rig.yaml: $HAIRRIG_ETC, then the etc/ of the source tree this
// binary was built from, then ./etc. NotFound names the places tried.
Result<std::string> DefaultRigConfigPath();
// Resolves a path given relative to the project's etc/ folder ("scenes/default.yaml").
Result<std::string> EtcPath(const std::string& relative);

Result<RigConfig> LoadRigConfig(const std::string& path);

struct Rig {
  RigConfig config;
  std::shared_ptr<SimWorld> sim_world;  // set when the config has a sim section
  DeviceSet devices;
};

// Builds every device (closed). The sim backend is available when the config
// has a `sim` section.
Result<std::unique_ptr<Rig>> BuildRig(const RigConfig& config);

}  // namespace hairrig
