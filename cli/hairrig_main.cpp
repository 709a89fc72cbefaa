#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>

#include "cli/cli.h"
#include "core/log.h"
#include "core/version.h"
#include "sim_rig/sim_rig.h"

namespace {

// The command line's own work: parse, dispatch, print.
int Run(int argc, char** argv) {
  using namespace hairrig;
  RegisterSimRig();  // rig configs with a `sim` section build the simulated rig
  CLI::App app{
      "hairrig: capture rig control and hair pipeline.\n"
      "With no --config, the rig is the simulated one in etc/ (etc/sim-rig.yaml)."};
  app.require_subcommand(1);
  const Result<std::string> build = HairrigBuildId();
  app.set_version_flag("--version", std::string(HairrigVersion()) + " (build " +
                                        (build.ok() ? *build : "unknown") + ")");
  CommonOptions common;
  app.add_option("--log-level", common.log_level, "debug, info, warning, error or off")
      ->capture_default_str();
  Dispatch dispatch;
  AddDevicesCommand(app, common, dispatch);
  AddCaptureCommand(app, common, dispatch);
  AddReplayCommand(app, common, dispatch);
  AddFitCommand(app, common, dispatch);
  AddSimulateCommand(app, common, dispatch);
  AddCalibrateCommand(app, common, dispatch);
  AddReconstructCommand(app, common, dispatch);
  AddExportCommand(app, common, dispatch);
  AddEvalCommand(app, common, dispatch);
  AddSimCommand(app, common, dispatch);
  AddStageCommand(app, common, dispatch);
  AddBatchCommand(app, common, dispatch);
  AddConsoleCommand(app, common, dispatch);
  AddEStopCommand(app, common, dispatch);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here with CLI11's exit code 0; every argument error is exit 1.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "hairrig: error: %s\n", e.what());
    return 1;
  }
  if (const Status valid = common.Check(); !valid.ok()) {
    std::fprintf(stderr, "hairrig: error: %s\n", valid.message().c_str());
    return 2;
  }
  LogLevel level = LogLevel::kInfo;
  if (ParseLogLevel(common.log_level, &level)) SetLogLevel(level);
  if (!dispatch.action) {
    std::cerr << app.help();
    return 2;
  }
  auto result = dispatch.action();
  if (!result.ok()) {
    std::fprintf(stderr, "hairrig: error: %s\n", result.status().ToString().c_str());
    return 1;
  }
  if (common.json) {
    std::cout << result->dump() << std::endl;
  } else if (dispatch.print_human) {
    dispatch.print_human(*result);
  }
  return dispatch.exit_code ? dispatch.exit_code(*result) : 0;
}

}  // namespace

// The libraries report failures as Status; anything thrown that reaches here
// is a bug, reported as an error instead of std::terminate.
int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hairrig: error: internal error (please report it): %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "hairrig: error: internal error (please report it): unknown exception\n");
  }
  return 1;
}
