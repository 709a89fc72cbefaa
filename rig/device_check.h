// `hairrig devices`: every device of a rig config built, opened and
// health-checked (drivers/device.h), then closed again.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct DeviceCheckOptions {
  std::string config_path;  // the rig config; empty: the simulated rig (DefaultRigConfigPath)

  // Every value is valid (an empty config_path is the simulated rig's).
  Status Check() const { return Status::Ok(); }
};

struct DeviceCheck {
  std::string name, kind, backend, serial, model;
  std::string state;   // after the check, before closing (drivers/device.h DeviceStateName)
  std::string health;  // "ok", or why opening or the health check failed
};

struct DeviceCheckSummary {
  std::string config_path;  // as loaded
  std::string rig_name;
  std::vector<DeviceCheck> devices;  // in the rig's order
  int healthy = 0;

  // config, rig, devices (each as DeviceCheck), healthy and total.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;  // a table, one device a line
};

// Errors: the config (named, with the field: its devices and the plan,
// retries, storage and calibration sections as a capture reads them) or a
// device that cannot be built from it; a device that fails to open or its health check is reported
// in the summary, not as an error.
Result<DeviceCheckSummary> CheckDevices(const DeviceCheckOptions& options);

}  // namespace hairrig
