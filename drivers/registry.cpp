#include "drivers/registry.h"

#include <set>

namespace hairrig {

std::vector<std::string> DeviceRegistry::BackendNames(DeviceKind kind) const {
  std::vector<std::string> names;
  for (const auto& [key, factory] : factories_) {
    if (key.first == kind) names.push_back(key.second);
  }
  return names;
}

Result<std::unique_ptr<Device>> DeviceRegistry::Create(const DeviceConfig& config) const {
  const auto it = factories_.find({config.kind, config.backend});
  if (it == factories_.end()) {
    std::string known;
    for (const auto& n : BackendNames(config.kind)) known += (known.empty() ? "" : ", ") + n;
    return NotFound(std::string("unknown ") + DeviceKindName(config.kind) + " backend '" +
                    config.backend + "' (this build has: " + (known.empty() ? "none" : known) +
                    ")");
  }
  return it->second(config);
}

std::vector<Device*> DeviceSet::All() const {
  std::vector<Device*> all;
  if (turntable) all.push_back(turntable.get());
  for (const auto& d : lights) all.push_back(d.get());
  for (const auto& d : trigger_lines) all.push_back(d.get());
  for (const auto& d : cameras) all.push_back(d.get());
  for (const auto& d : input_lines) all.push_back(d.get());
  return all;
}

Camera* DeviceSet::FindCameraBySerial(const std::string& serial) const {
  for (const auto& c : cameras) {
    if (c->info().serial == serial) return c.get();
  }
  return nullptr;
}

Status DeviceSet::OpenAll() {
  Status first;
  for (Device* d : All()) {
    Status s = d->Open();
    if (!s.ok() && first.ok()) first = s;
  }
  return first;
}

void DeviceSet::CloseAll() {
  for (Device* d : All()) (void)d->Close();
}

namespace {

class DeviceBuilder {
 public:
  DeviceBuilder(const DeviceRegistry& registry, std::string backend_override)
      : registry_(registry), backend_override_(std::move(backend_override)) {}

  // Creates one device of `kind` from `node`; nullptr after recording an error.
  template <typename T>
  std::unique_ptr<T> Build(DeviceKind kind, const ConfigNode& node) {
    DeviceConfig config;
    config.kind = kind;
    config.node = node;
    config.name = node.String("name");
    config.backend = node.String("backend");
    config.serial = node.String("serial");
    if (!node.ok()) return nullptr;
    if (!backend_override_.empty()) config.backend = backend_override_;
    if (config.serial.empty()) {
      node.Fail("serial", "a device is identified by its serial number; it may not be empty");
      return nullptr;
    }
    if (!serials_.insert(config.serial).second) {
      node.Fail("serial", "serial '" + config.serial + "' is used by two devices");
      return nullptr;
    }
    if (!names_.insert(config.name).second) {
      node.Fail("name", "name '" + config.name + "' is used by two devices");
      return nullptr;
    }
    auto made = registry_.Create(config);
    if (!made.ok()) {
      node.Fail("backend", made.status().message());
      return nullptr;
    }
    return std::unique_ptr<T>(static_cast<T*>(std::move(made).value().release()));
  }

 private:
  const DeviceRegistry& registry_;
  std::string backend_override_;
  std::set<std::string> serials_, names_;
};

}  // namespace

Result<DeviceSet> BuildDevices(const ConfigNode& devices, const DeviceRegistry& registry,
                               const std::string& backend_override) {
  devices.AllowOnlyKeys({"turntable", "lights", "trigger_lines", "cameras", "input_lines"});
  DeviceBuilder builder(registry, backend_override);
  DeviceSet set;
  if (devices.Has("turntable"))
    set.turntable = builder.Build<Turntable>(DeviceKind::kTurntable, devices.Child("turntable"));
  for (const auto& n : devices.OptionalItems("lights")) {
    if (auto d = builder.Build<Light>(DeviceKind::kLight, n)) set.lights.push_back(std::move(d));
  }
  for (const auto& n : devices.OptionalItems("trigger_lines")) {
    if (auto d = builder.Build<TriggerLine>(DeviceKind::kTriggerLine, n))
      set.trigger_lines.push_back(std::move(d));
  }
  for (const auto& n : devices.Items("cameras")) {
    if (auto d = builder.Build<Camera>(DeviceKind::kCamera, n)) set.cameras.push_back(std::move(d));
  }
  for (const auto& n : devices.OptionalItems("input_lines")) {
    if (auto d = builder.Build<InputLine>(DeviceKind::kInputLine, n))
      set.input_lines.push_back(std::move(d));
  }
  if (!devices.ok()) return devices.status();
  return set;
}

}  // namespace hairrig
