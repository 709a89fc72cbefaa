// A batch folder (`hairrig batch ... --batch DIR`) keeps a batch's state:
//
//   DIR/batch.json     the captures and every submission, rewritten atomically:
//     {"format": "hairrig-batch", "version": 1, "created_utc": "...",
//      "captures": ["/archive/cap1", ...],        absolute paths
//      "submissions": [{"run_id": "r1-20261124T101500-3fa2c1", "engine": "slurm",
//                       "stages": ["calibrate", ...],
//                       "captures": [0, 2, ...],                 indices into captures
//                       "submitted_utc": "...", "max_parallel": 4, "partition": "",
//                       "time_limit": {"reconstruct": "2:00:00"}, "mem": {"*": "8G"},
//                       "job_ids": {"calibrate": "1041", ...},   Slurm array job ids
//                       "runner": {"host": "...", "pid": 4242, "start_ticks": 123}}]}
//                                                                the local runner
//   DIR/batch.lock     held (flock) by a command that changes batch.json
//   DIR/runs/<run id>/ one submission: stage_options.json (every option, as the jobs read them),
//                      logs/<stage>_<i>.log (i: the capture's place in the submission's list),
//                      and for Slurm the job scripts <stage>.sbatch
//
// A capture's state is decided by the latest submission that holds it.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

enum class EngineKind { kLocal, kSlurm };
const char* EngineName(EngineKind engine);  // "local", "slurm"
Result<EngineKind> ParseEngine(const std::string& name);

struct Submission {
  std::string run_id;
  EngineKind engine = EngineKind::kLocal;
  std::vector<Stage> stages;  // in pipeline order
  std::vector<size_t>
      captures;  // indices into BatchState::captures; a job's index is the place here
  std::string submitted_utc;
  int max_parallel = 0;   // captures processed at once (Slurm: the array's %K); 0: no limit
  std::string partition;  // Slurm
  // Per stage name ("*": every stage without its own), Slurm's --time and --mem.
  std::map<std::string, std::string> time_limit, mem;
  std::map<std::string, std::string> job_ids;  // Slurm: stage name -> array job id
  std::string runner_host;                     // local: the process running the stages
  int64_t runner_pid = 0;
  uint64_t runner_start_ticks = 0;

  bool Holds(Stage stage) const;
  // The capture's place in `captures`, or -1.
  int IndexOf(size_t capture) const;
  std::string RunDir(const std::string& batch_dir) const;
  std::string OptionsFile(const std::string& batch_dir) const;
  std::string LogFile(const std::string& batch_dir, Stage stage, size_t index) const;
  // `values`' entry for the stage, else its "*" entry, else "".
  static std::string ForStage(const std::map<std::string, std::string>& values, Stage stage);
};

struct BatchState {
  std::string created_utc;
  std::vector<std::string> captures;
  std::vector<Submission> submissions;

  // The latest submission holding capture `capture` and stage `stage`, or null.
  const Submission* LatestFor(size_t capture, Stage stage) const;
};

// NotFound when DIR holds no batch.json; CorruptData naming the field.
Result<BatchState> ReadBatchState(const std::string& batch_dir);
Status WriteBatchState(const std::string& batch_dir, const BatchState& state);

// An exclusive lock on DIR/batch.lock, released when destroyed.
class BatchLock {
 public:
  // FailedPrecondition when another command holds it (a submit still running).
  static Result<BatchLock> Acquire(const std::string& batch_dir);
  BatchLock(BatchLock&& other) noexcept;
  BatchLock& operator=(BatchLock&&) = delete;
  BatchLock(const BatchLock&) = delete;
  BatchLock& operator=(const BatchLock&) = delete;
  ~BatchLock();

 private:
  explicit BatchLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

// A capture folder holds journal.jsonl and capture.json (rig/capture_dataset.h).
bool IsCaptureFolder(const std::string& dir);
// The capture folders `source` names: a file listing them (one a line; blank
// lines and lines starting with '#' skipped; relative paths against the
// file's folder), in its order; or a folder, searched for capture folders
// (not inside them), sorted by path. Absolute and normalised. Errors:
// NotFound for `source`; InvalidArgument naming a listed path that is not a
// capture folder, one listed twice, a path with a newline, or no capture at all.
Result<std::vector<std::string>> FindCaptures(const std::string& source);

// "r<N>-<UTC time>-<6 random hex digits>": unique across batches.
std::string NewRunId(size_t submission_number);

}  // namespace hairrig
