// `hairrig batch`: the pipeline's stages over an archive of captures
// (docs/design.md section 10), with the local engine (the default) or on a Slurm
// cluster (batch/engine.h). The batch folder keeps its state
// (batch/batch_state.h).
//
// Each (capture, stage) is reported as one of:
//   done      its result.json of this submission says ok
//   skipped   ... ok, and its inputs were unchanged since an earlier success
//   failed    its result says failed (with the error), or its job ended
//             without a finished result (killed, out of time or memory, a
//             job Slurm calls COMPLETED that wrote nothing)
//   blocked   an earlier stage of the capture failed or was blocked
//   pending   its job has not started
//   running   its job runs
// "This submission" is the latest one holding the capture and the stage.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "batch/batch_state.h"
#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

struct SubmitOptions {
  std::string batch_dir;
  // A file listing capture folders or a folder of captures (FindCaptures).
  // Required to start a batch; afterwards, if given, it must name the same captures.
  std::string captures;
  std::optional<EngineKind> engine;  // unset: the batch's latest submission's, else local
  std::vector<Stage> stages;         // empty: the batch's latest submission's, else every stage
  // The stage options file (batch/stages.h); empty: the latest submission's, else the defaults.
  std::string stage_options;
  std::optional<int> max_parallel;       // captures at once; unset: the latest submission's, else 2
  std::optional<std::string> partition;  // Slurm; unset: the latest submission's
  // Slurm's --time and --mem: "VALUE" for every stage or "STAGE=VALUE", each
  // entry over the latest submission's; empty: the latest submission's.
  std::vector<std::string> time_limit, mem;
  std::string hairrig_exe;  // the absolute path of the hairrig binary the jobs run

  // InvalidArgument naming the field: no batch_dir, a negative max_parallel,
  // no hairrig_exe.
  Status Check() const;
};

struct StageCell {
  std::string state;  // done, skipped, failed, blocked, pending, running, or "" (never submitted)
  std::string error;  // failed: why; blocked: by which stage
  std::string run_id;
  std::string input_hash;  // from result.json (done, skipped, failed)
  double seconds = 0;      // of the run that made the outputs
  std::string log;         // the job's log file
};

struct CaptureReport {
  std::string capture;
  std::vector<StageCell> stages;  // as BatchReport::stages
};

struct BatchReport {
  std::string batch_dir;
  std::vector<Stage> stages;  // every stage any submission holds, in pipeline order
  std::vector<CaptureReport> captures;

  int Count(const std::string& state) const;
  // Nothing pending or running.
  bool Finished() const;
  // Everything submitted is done or skipped.
  bool AllSucceeded() const;
  nlohmann::json ToJson() const;
  // A table: a row per capture, a column per stage, then the failures' errors and logs.
  std::string Table() const;
  // One line of counts: "3 captures x 4 stages: 10 done, 1 failed, 1 blocked".
  std::string BriefReport() const;
};

struct SubmitSummary {
  std::string batch_dir;
  std::string run_id;  // empty when nothing was submitted
  EngineKind engine = EngineKind::kLocal;
  std::vector<Stage> stages;
  std::vector<std::string> captures;
  std::map<std::string, std::string> job_ids;  // Slurm: stage -> array job id
  BatchReport report;                          // after submitting (local: after running)
  nlohmann::json ToJson() const;
};

// Starts a batch in an empty or new folder, or submits every capture of an
// existing batch again (stages whose inputs are unchanged then skip). The
// local engine runs the submission to its end before returning; Slurm's
// returns once the arrays are queued. Errors: InvalidArgument for bad
// options or captures; FailedPrecondition when another command holds the
// batch folder; the engine's error (sbatch's message) with nothing recorded.
Result<SubmitSummary> SubmitBatch(const SubmitOptions& options);

// Submits again, as one new submission, every capture with a failed or
// blocked stage in the latest report, for the stages of its latest
// submission (earlier successful stages skip). `options.captures` is
// ignored. An empty summary (no run id) when nothing failed.
Result<SubmitSummary> ResubmitFailed(const SubmitOptions& options);

// Every capture's state per stage, from the result files and the engines.
// Errors: the batch folder's (ReadBatchState) or an engine that cannot be asked.
Result<BatchReport> ReportBatch(const std::string& batch_dir);

// Polls ReportBatch every `poll_s` until it is finished; Timeout after
// `timeout_s` (<= 0: no limit) saying how many jobs remain.
Result<BatchReport> WaitForBatch(const std::string& batch_dir, double timeout_s,
                                 double poll_s = 2.0);

}  // namespace hairrig
