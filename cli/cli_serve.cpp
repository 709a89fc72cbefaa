#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "cli/cli.h"
#include "console/console_server.h"
#include "console/estop_client.h"

namespace hairrig {
namespace {

std::atomic<bool> g_stop_serving{false};

void OnStopSignal(int) { g_stop_serving = true; }

}  // namespace

void AddConsoleCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "serve", "Run the operator console: the rig's devices, a web page and a JSON API");
  auto options = std::make_shared<ConsoleOptions>();
  options->rig.captures_dir = "captures";
  cmd->add_option("--config", options->rig.config_path,
                  "rig config (default: etc/sim-rig.yaml, the simulated rig)");
  cmd->add_option("--listen", options->listen,
                  "host:port to listen on; beyond loopback a token is required")
      ->capture_default_str();
  cmd->add_option("--captures", options->rig.captures_dir,
                  "folder of captures: new captures go here, the archive lists it")
      ->capture_default_str();
  cmd->add_option("--token", options->token,
                  "token every API request must carry (default: $HAIRRIG_CONSOLE_TOKEN)");
  cmd->add_option("--live-fps", options->rig.live.fps, "live-view frames per second per camera")
      ->capture_default_str();
  cmd->add_option("--threads", options->rig.threads,
                  "threads for tag detection, calibration and reconstruction after a capture")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object when it stops");
  cmd->callback([options, &dispatch] {
    if (options->token.empty()) {
      if (const char* env = std::getenv("HAIRRIG_CONSOLE_TOKEN")) options->token = env;
    }
    const Status valid = options->Check();
    if (!valid.ok()) throw CLI::ValidationError("serve", valid.message());
    std::signal(SIGINT, OnStopSignal);
    std::signal(SIGTERM, OnStopSignal);
    DispatchSummary(dispatch, [options] {
      return RunConsole(*options, g_stop_serving, [](const std::string& url) {
        std::fprintf(stderr, "hairrig serve: the console is at %s (Ctrl-C stops it)\n",
                     url.c_str());
      });
    });
  });
}

void AddEStopCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "estop",
      "Press a running console's e-stop (a software path: the rig's hardware e-stop "
      "is the one to rely on)");
  auto request = std::make_shared<EStopRequest>();
  cmd->add_option("--console", request->url, "the console's URL, as `hairrig serve` prints it")
      ->capture_default_str();
  cmd->add_option("--token", request->token,
                  "the console's token, beyond loopback (default: $HAIRRIG_CONSOLE_TOKEN)");
  auto timeout_ms = std::make_shared<int>(static_cast<int>(request->timeout.count()));
  cmd->add_option("--timeout-ms", *timeout_ms, "how long to wait for the console's answer")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([request, timeout_ms, &dispatch] {
    if (request->token.empty()) {
      if (const char* env = std::getenv("HAIRRIG_CONSOLE_TOKEN")) request->token = env;
    }
    request->timeout = std::chrono::milliseconds(*timeout_ms);
    DispatchSummary(dispatch, [request] { return PressConsoleEStop(*request); });
  });
}

}  // namespace hairrig
