#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/cli.h"
#include "rig/device_check.h"
#include "rig/device_discovery.h"

namespace hairrig {
namespace {

Result<nlohmann::json> RunDiscover() {
  const Discovery discovery = DiscoverDevices();
  nlohmann::json out = DiscoveryToJson(discovery);
  out["text"] = DiscoveryText(discovery);
  return out;
}

}  // namespace

void AddDevicesCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "devices",
      "List the configured devices with serial, backend and state, and health-check them");
  auto options = std::make_shared<DeviceCheckOptions>();
  auto discover = std::make_shared<bool>(false);
  auto* config_option =
      cmd->add_option("--config", options->config_path,
                      "rig config (default: etc/sim-rig.yaml, the simulated rig)");
  cmd->add_flag("--discover", *discover,
                "find the real devices connected to this machine and print each with its serial "
                "and a config snippet")
      ->excludes(config_option);
  cmd->add_flag("--json", common.json, "print the result as one JSON object");
  cmd->callback([options, discover, &dispatch] {
    if (*discover) {
      dispatch.action = [] { return RunDiscover(); };
      dispatch.print_human = [](const nlohmann::json& j) {
        std::fputs(j["text"].get<std::string>().c_str(), stdout);
      };
      return;
    }
    DispatchSummary(dispatch, [options] { return CheckDevices(*options); });
    // A rig with a device that fails to open or its health check is not ready.
    dispatch.exit_code = [](const nlohmann::json& j) { return j["healthy"] == j["total"] ? 0 : 3; };
  });
}

}  // namespace hairrig
