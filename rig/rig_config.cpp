#include "rig/rig_config.h"

#include <cstdlib>
#include <filesystem>

#include "core/head_config.h"
#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/gpio_devices.h"
#include "drivers/modbus_turntable.h"
#include "drivers/usb_relay.h"
#include "drivers/v4l2_camera.h"
#include "rig/rig_extension.h"

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
  return NotFound("cannot find " + relative + " (tried " + tried +
                  "); set HAIRRIG_ETC to the project's etc/ folder");
}

Result<std::string> DefaultRigConfigPath() { return EtcPath("sim-rig.yaml"); }

Result<RigConfig> LoadRigConfig(const std::string& path, const std::string& relative_to,
                                UnclaimedSections unclaimed) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  const std::vector<std::shared_ptr<const RigExtension>> extensions = RegisteredRigExtensions();
  if (unclaimed == UnclaimedSections::kRefuse) {
    std::vector<std::string> sections{"name",    "devices",     "plan", "storage",
                                      "retries", "calibration", "head"};
    for (const auto& extension : extensions) {
      for (const std::string& section : extension->ConfigSections()) sections.push_back(section);
    }
    root.AllowOnlyKeys(sections);
  }
  RigConfig config;
  config.path = path;
  config.relative_to =
      relative_to.empty() ? fs::absolute(path).parent_path().string() : relative_to;
  config.root = root;
  config.name = root.String("name", fs::path(path).stem().string());
  for (const auto& extension : extensions) HR_RETURN_IF_ERROR(extension->CheckConfig(config));
  if (root.Has("head")) {
    config.head.emplace();
    // ReadHeadConfig resolves relative paths beside a file: one inside relative_to.
    HR_RETURN_IF_ERROR(ReadHeadConfig(
        root, "head", (fs::path(config.relative_to) / "rig.yaml").string(), &*config.head));
  }
  root.Child("devices");
  if (!root.ok()) return root.status();
  return config;
}

namespace {

// Runs `hooks` in order; the first error stops them.
template <typename Options>
std::function<Status(const DeviceConfig&, Options*)> Chained(
    std::vector<std::function<Status(const DeviceConfig&, Options*)>> hooks) {
  return [hooks = std::move(hooks)](const DeviceConfig& config, Options* options) {
    for (const auto& hook : hooks) HR_RETURN_IF_ERROR(hook(config, options));
    return Status::Ok();
  };
}

// Registers the real backends, each running the extensions' hooks on its options.
void RegisterRealBackends(DeviceRegistry* registry, const RigBackendHooks& hooks) {
  RegisterGpioBackends(registry, MakeLibgpiodProvider());
  RegisterModbusTurntableBackend(registry, Chained(hooks.modbus));
  RegisterGphoto2Backend(registry, Chained(hooks.gphoto2));
  RegisterAravisBackend(registry, Chained(hooks.aravis));
  RegisterV4l2Backend(registry, Chained(hooks.v4l2));
  RegisterUsbRelayBackend(registry, Chained(hooks.usb_relay), hooks.usb_relay_fields);
}

}  // namespace

Result<std::unique_ptr<Rig>> BuildRig(const RigConfig& config, const RigBuildOptions& build) {
  HR_RETURN_IF_ERROR(build.Check());
  auto rig = std::make_unique<Rig>();
  rig->config = config;
  DeviceRegistry registry;
  if (build.register_backends) build.register_backends(&registry);
  RigBackendHooks hooks;
  if (build.attach_extensions) {
    RigAssembly assembly{config, *rig, registry, hooks};
    for (const auto& extension : RegisteredRigExtensions()) {
      HR_RETURN_IF_ERROR(extension->Attach(assembly));
    }
  }
  RegisterRealBackends(&registry, hooks);
  HR_ASSIGN_OR_RETURN(rig->devices,
                      BuildDevices(config.root.Child("devices"), registry, build.backend_override));
  for (const ConfigNode& camera : config.root.Child("devices").Items("cameras")) {
    const std::string line = camera.String("trigger_line", "");
    if (line.empty()) continue;
    bool known = false;
    for (const auto& l : rig->devices.trigger_lines) known = known || l->info().name == line;
    if (!known)
      camera.Fail("trigger_line", "no trigger line named '" + line + "' in devices.trigger_lines");
    rig->camera_trigger_lines[camera.String("name")] = line;
  }
  if (!config.root.ok()) return config.root.status();
  if (build.on_built) build.on_built(*rig);
  return rig;
}

}  // namespace hairrig
