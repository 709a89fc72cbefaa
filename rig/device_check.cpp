#include "rig/device_check.h"

#include <nlohmann/json.hpp>

#include "core/string_format.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"

namespace hairrig {

namespace {

DeviceCheck Check(Device& device) {
  Status s = device.Open();
  if (s.ok()) s = device.HealthCheck();
  const DeviceInfo& info = device.info();
  return {info.name,
          DeviceKindName(info.kind),
          info.backend,
          info.serial,
          info.model,
          DeviceStateName(device.state()),
          s.ok() ? "ok" : s.ToString()};
}

}  // namespace

nlohmann::json DeviceCheckSummary::ToJson() const {
  nlohmann::json out{
      {"config", config_path}, {"rig", rig_name}, {"devices", nlohmann::json::array()}};
  for (const DeviceCheck& d : devices) {
    out["devices"].push_back({{"name", d.name},
                              {"kind", d.kind},
                              {"backend", d.backend},
                              {"serial", d.serial},
                              {"model", d.model},
                              {"state", d.state},
                              {"health", d.health}});
  }
  out["healthy"] = healthy;
  out["total"] = devices.size();
  return out;
}

std::string DeviceCheckSummary::BriefReport() const {
  std::string text = StringPrintf("rig: %s (%s)\n", rig_name.c_str(), config_path.c_str());
  text += StringPrintf("%-10s %-13s %-8s %-16s %-8s %s\n", "NAME", "KIND", "BACKEND", "SERIAL",
                       "STATE", "HEALTH");
  for (const DeviceCheck& d : devices) {
    text += StringPrintf("%-10s %-13s %-8s %-16s %-8s %s\n", d.name.c_str(), d.kind.c_str(),
                         d.backend.c_str(), d.serial.c_str(), d.state.c_str(), d.health.c_str());
  }
  text += StringPrintf("%d of %d devices healthy\n", healthy, static_cast<int>(devices.size()));
  return text;
}

Result<DeviceCheckSummary> CheckDevices(const DeviceCheckOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  std::string path = options.config_path;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, DefaultRigConfigPath());
  }
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadRigConfig(path));
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Rig> rig, BuildRig(config));
  // The sections a capture and its calibration read, checked as they will read them.
  HR_RETURN_IF_ERROR(ReadCapturePlan(config.root, rig->devices).status());
  HR_RETURN_IF_ERROR(ReadCapturePolicies(config.root).status());
  HR_RETURN_IF_ERROR(CheckCalibrationSection(config));
  DeviceCheckSummary summary;
  summary.config_path = config.path;
  summary.rig_name = config.name;
  for (Device* device : rig->devices.All()) {
    summary.devices.push_back(Check(*device));
    summary.healthy += summary.devices.back().health == "ok" ? 1 : 0;
  }
  rig->devices.CloseAll();
  return summary;
}

}  // namespace hairrig
