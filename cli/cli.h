// The `hairrig` command line: each subcommand parses, validates, calls the
// libraries and writes; no algorithm lives here (docs/design.md section 7).
#pragma once

#include <cstdio>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>

#include "core/log.h"
#include "core/status.h"

namespace CLI {
class App;
}

namespace hairrig {

// Options every subcommand shares.
struct CommonOptions {
  bool json = false;  // print the summary as one JSON object on stdout
  std::string log_level = "info";

  // InvalidArgument naming --log-level when it is not one of debug, info,
  // warning, error, off.
  Status Check() const {
    LogLevel level;
    if (ParseLogLevel(log_level, &level)) return Status::Ok();
    return InvalidArgument("--log-level '" + log_level +
                           "' is not one of debug, info, warning, error, off");
  }
};

// A subcommand's work: returns its summary as JSON, or a Status for the error.
using CommandAction = std::function<Result<nlohmann::json>()>;
// What main runs after parsing.
struct Dispatch {
  CommandAction action;
  std::function<void(const nlohmann::json&)> print_human;
  // Exit code for a summary (a capture stopped by a fault is not a success); 0 when unset.
  std::function<int(const nlohmann::json&)> exit_code;
};

// Sets `dispatch` to run `run`, the subcommand's one library call (returning
// Result<Summary>), and to print its summary: Summary::ToJson() with --json,
// else Summary::BriefReport().
template <typename Run>
void DispatchSummary(Dispatch& dispatch, Run run) {
  using Summary = std::decay_t<decltype(std::declval<Run&>()().value())>;
  auto summary = std::make_shared<Summary>();
  dispatch.action = [run = std::move(run), summary]() mutable -> Result<nlohmann::json> {
    HR_ASSIGN_OR_RETURN(*summary, run());
    return summary->ToJson();
  };
  dispatch.print_human = [summary](const nlohmann::json&) {
    std::fputs(summary->BriefReport().c_str(), stdout);
  };
}

// The exit code of a command whose summary carries a verdict: 3 when it is "failed".
inline int FailedVerdictExitCode(const nlohmann::json& summary) {
  return summary["verdict"] == "failed" ? 3 : 0;
}

void AddDevicesCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddSimCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddCaptureCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddReplayCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddFitCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddSimulateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddCalibrateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddEvalCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddReconstructCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddExportCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddStageCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddBatchCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
// `hairrig serve`: the operator console (console/console_server.h).
void AddConsoleCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddEStopCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);

}  // namespace hairrig
