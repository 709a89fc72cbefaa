// The `hairrig` command line: each subcommand parses, validates, calls the
// libraries and writes; no algorithm lives here (design.md section 7).
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/status.h"

namespace CLI {
class App;
}

namespace hairrig {

// Options every subcommand shares.
struct CommonOptions {
  bool json = false;      // print the summary as one JSON object on stdout
  std::string log_level = "info";
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

struct CalibratedFolder;
// `calibrate`'s summary (also printed by `capture --calibrate`).
nlohmann::json CalibrationSummaryJson(const CalibratedFolder& done);
void PrintCalibrationSummary(const nlohmann::json& summary);

void AddDevicesCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddSimCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddCaptureCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddReplayCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddFitCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddSimulateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddCalibrateCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddEvalCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddReconstructCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddStageCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);
void AddBatchCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch);

}  // namespace hairrig
