#include <cstdio>

#include <CLI/CLI.hpp>

#include "rig/cli.h"
#include "rig/device_discovery.h"
#include "rig/rig_config.h"

namespace hairrig {
namespace {

Result<RigConfig> LoadConfigOrDefault(const std::string& config_path) {
  std::string path = config_path;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, DefaultRigConfigPath());
  }
  return LoadRigConfig(path);
}

Result<nlohmann::json> RunDevices(const std::string& config_path) {
  HR_ASSIGN_OR_RETURN(RigConfig config, LoadConfigOrDefault(config_path));
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Rig> rig, BuildRig(config));
  nlohmann::json out;
  out["config"] = config.path;
  out["rig"] = config.name;
  out["devices"] = nlohmann::json::array();
  int healthy = 0;
  for (Device* d : rig->devices.All()) {
    Status s = d->Open();
    if (s.ok()) s = d->HealthCheck();
    healthy += s.ok() ? 1 : 0;
    out["devices"].push_back({{"name", d->info().name},
                              {"kind", DeviceKindName(d->info().kind)},
                              {"backend", d->info().backend},
                              {"serial", d->info().serial},
                              {"model", d->info().model},
                              {"state", DeviceStateName(d->state())},
                              {"health", s.ok() ? "ok" : s.ToString()}});
  }
  rig->devices.CloseAll();
  out["healthy"] = healthy;
  out["total"] = out["devices"].size();
  return out;
}

Result<nlohmann::json> RunDiscover() {
  const Discovery discovery = DiscoverDevices();
  nlohmann::json out = DiscoveryToJson(discovery);
  out["text"] = DiscoveryText(discovery);
  return out;
}

void PrintDevices(const nlohmann::json& j) {
  std::printf("rig: %s (%s)\n", j["rig"].get<std::string>().c_str(), j["config"].get<std::string>().c_str());
  std::printf("%-10s %-13s %-8s %-16s %-8s %s\n", "NAME", "KIND", "BACKEND", "SERIAL", "STATE", "HEALTH");
  for (const auto& d : j["devices"]) {
    std::printf("%-10s %-13s %-8s %-16s %-8s %s\n", d["name"].get<std::string>().c_str(),
                d["kind"].get<std::string>().c_str(), d["backend"].get<std::string>().c_str(),
                d["serial"].get<std::string>().c_str(), d["state"].get<std::string>().c_str(),
                d["health"].get<std::string>().c_str());
  }
  std::printf("%d of %d devices healthy\n", j["healthy"].get<int>(), j["total"].get<int>());
}

}  // namespace

void AddDevicesCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("devices", "List the configured devices with serial, backend and state, and health-check them");
  auto config = std::make_shared<std::string>();
  auto discover = std::make_shared<bool>(false);
  auto* config_option =
      cmd->add_option("--config", *config, "rig config (default: etc/sim-rig.yaml, the simulated rig)");
  cmd->add_flag("--discover", *discover,
                "find the real devices connected to this machine and print each with its serial and a config snippet")
      ->excludes(config_option);
  cmd->add_flag("--json", common.json, "print the result as one JSON object");
  cmd->callback([config, discover, &dispatch] {
    if (*discover) {
      dispatch.action = [] { return RunDiscover(); };
      dispatch.print_human = [](const nlohmann::json& j) { std::fputs(j["text"].get<std::string>().c_str(), stdout); };
      return;
    }
    dispatch.action = [config] { return RunDevices(*config); };
    dispatch.print_human = PrintDevices;
  });
}

}  // namespace hairrig
