// Builds devices from the rig config by backend name.
//
// The `devices` section of a rig config:
//   devices:
//     turntable: {name: turntable, backend: sim, serial: SIM-TT-0001, ...backend fields}
//     lights:        [{name: top, backend: sim, serial: ...}, ...]
//     trigger_lines: [{name: trig0, backend: sim, serial: ...}]
//     cameras:       [{name: upper, backend: sim, serial: ..., trigger_line: trig0}]
//     input_lines:   [{name: estop, backend: sim, serial: ...}]   (safety inputs)
// Backends register a factory per kind; the registry knows none of them, so
// drivers/ stays free of sim_hw/ and the simulated rig's plug point
// (sim_rig/sim_rig.h) wires the two together.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "drivers/camera.h"
#include "drivers/input_line.h"
#include "drivers/light.h"
#include "drivers/trigger_line.h"
#include "drivers/turntable.h"

namespace hairrig {

struct DeviceConfig {
  DeviceKind kind = DeviceKind::kCamera;
  std::string name;
  std::string backend;
  std::string serial;
  ConfigNode node;  // the device's map, for backend-specific fields
  DeviceInfo Info(const std::string& model) const { return {kind, name, backend, serial, model}; }
};

class DeviceRegistry {
 public:
  template <typename T>
  using Factory = std::function<Result<std::unique_ptr<T>>(const DeviceConfig&)>;

  template <typename T>
  void AddBackend(DeviceKind kind, const std::string& backend, Factory<T> factory) {
    factories_[{kind, backend}] =
        [factory](const DeviceConfig& c) -> Result<std::unique_ptr<Device>> {
      auto made = factory(c);
      if (!made.ok()) return made.status();
      return std::unique_ptr<Device>(std::move(made).value());
    };
  }
  std::vector<std::string> BackendNames(DeviceKind kind) const;
  // NotFound (listing the known backends) if `config.backend` is not registered for its kind.
  Result<std::unique_ptr<Device>> Create(const DeviceConfig& config) const;

 private:
  std::map<std::pair<DeviceKind, std::string>, Factory<Device>> factories_;
};

struct DeviceSet {
  std::unique_ptr<Turntable> turntable;
  std::vector<std::unique_ptr<Light>> lights;
  std::vector<std::unique_ptr<TriggerLine>> trigger_lines;
  std::vector<std::unique_ptr<Camera>> cameras;
  std::vector<std::unique_ptr<InputLine>> input_lines;

  std::vector<Device*> All() const;
  Camera* FindCameraBySerial(const std::string& serial) const;
  Status OpenAll();  // first failure named; the rest still attempted
  void CloseAll();
};

// Reads the `devices` section. Errors name the file, line and field (unknown
// backend, missing or duplicate serial, duplicate name).
// With `backend_override` every device is built by that backend instead of
// its configured one (a replay stands in for a whole recorded rig).
Result<DeviceSet> BuildDevices(const ConfigNode& devices, const DeviceRegistry& registry,
                               const std::string& backend_override = "");

}  // namespace hairrig
