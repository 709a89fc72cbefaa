// A stage's record of its last run: <capture>/<stage folder>/result.json
// (batch/stages.h names the folders), written atomically (core/file_util.h
// WriteFileAtomic):
//
//   {"format": "hairrig-stage-result", "version": 1,
//    "stage": "reconstruct", "status": "ok" | "failed" | "running",
//    "skipped": false,            // true: inputs unchanged since this success; nothing ran
//    "hairrig_version": "0.1.0",
//    "hairrig_build": "<id>",     // the executable's build (core/version.h HairrigBuildId)
//    "input_hash": "<sha256>",    // over the version, build, stage, options and inputs' contents
//    "inputs": {"frames/000_SIM-CAM-UPPER.png": "<sha256>", ...},   // the inputs' own hashes
//    "options": {...},            // the stage's options (batch/stages.h StageSettings::StageJson)
//    "run_id": "r1-...",          // the batch submission that ran or skipped it; "" outside one
//    "host": "node12", "pid": 4242,
//    "start_utc": "...", "end_utc": "...", "seconds": 12.5,   // the run that made the outputs
//    "checked_utc": "...",        // when a skipped run found the inputs unchanged
//    "error": "...",              // status failed: why
//    "injected_fault": false,     // the failure is HAIRRIG_STAGE_FAULT's (batch/stage.h)
//    "summary": {...}}            // the stage's summary (status ok)
//
// "running" is written when the stage starts, so a run that dies (killed,
// out of memory or out of time) leaves a record that says it never finished.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

struct StageRecord {
  std::string stage;
  std::string status;  // "ok", "failed" or "running"
  bool skipped = false;
  bool injected_fault = false;
  std::string hairrig_version;
  std::string hairrig_build;
  std::string input_hash;
  nlohmann::json inputs = nlohmann::json::object();
  nlohmann::json options = nlohmann::json::object();
  std::string run_id;
  std::string host;
  int64_t pid = 0;
  std::string start_utc, end_utc, checked_utc;
  double seconds = 0;
  std::string error;
  nlohmann::json summary = nlohmann::json::object();

  bool ok() const { return status == "ok"; }
  nlohmann::json ToJson() const;
};

// <capture_dir>/<StageFolder(stage)>/result.json.
std::string StageRecordPath(const std::string& capture_dir, Stage stage);
// NotFound when there is no record; CorruptData naming the file and field
// for a damaged one.
Result<StageRecord> ReadStageRecord(const std::string& capture_dir, Stage stage);
// Creates the stage folder if needed; IoError names the file.
Status WriteStageRecord(const std::string& capture_dir, Stage stage, const StageRecord& record);

}  // namespace hairrig
