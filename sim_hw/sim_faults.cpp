#include "sim_hw/sim_faults.h"

#include <utility>

namespace hairrig {
namespace {

constexpr std::pair<SimFaultKind, const char*> kKindNames[] = {
    {SimFaultKind::kDropFrame, "drop_frame"},
    {SimFaultKind::kCameraGone, "camera_gone"},
    {SimFaultKind::kDownloadTimeout, "download_timeout"},
    {SimFaultKind::kTurntableTimeout, "turntable_timeout"},
    {SimFaultKind::kTurntableStall, "turntable_stall"},
    {SimFaultKind::kEstop, "estop"},
    {SimFaultKind::kInputLost, "input_lost"},
    {SimFaultKind::kDiskFull, "disk_full"},
};

bool IsCameraFault(SimFaultKind kind) {
  return kind == SimFaultKind::kDropFrame || kind == SimFaultKind::kCameraGone ||
         kind == SimFaultKind::kDownloadTimeout;
}

}  // namespace

const char* SimFaultKindName(SimFaultKind kind) {
  for (const auto& [k, name] : kKindNames) {
    if (k == kind) return name;
  }
  return "?";
}

Result<std::vector<SimFault>> ParseSimFaults(const ConfigNode& faults) {
  std::vector<SimFault> out;
  for (const ConfigNode& node : faults.OptionalItems("faults")) {
    node.AllowOnlyKeys({"kind", "device", "at", "count", "delay_s"});
    SimFault fault;
    const std::string kind =
        node.Choice("kind", {"drop_frame", "camera_gone", "download_timeout", "turntable_timeout",
                             "turntable_stall", "estop", "input_lost", "disk_full"});
    for (const auto& [k, name] : kKindNames) {
      if (kind == name) fault.kind = k;
    }
    fault.device = node.String("device", "");
    // A capture has a few hundred events per device and waits minutes at
    // most: a million events and an hour of device time are far beyond any test.
    fault.at = node.Integer("at", 1, {.min = 1, .max = 1e6});
    fault.count = node.Integer("count", 1, {.min = 1, .max = 1e6});
    fault.delay_s = node.Number("delay_s", fault.delay_s, {.min = 0, .max = 3600});
    if (node.ok() && IsCameraFault(fault.kind) && fault.device.empty()) {
      node.Fail("device",
                std::string("a ") + kind + " fault needs the serial of the camera it hits");
    }
    out.push_back(fault);
  }
  if (!faults.ok()) return faults.status();
  return out;
}

}  // namespace hairrig
