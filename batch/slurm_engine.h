// The Slurm engine: one job array per stage, one element per capture
// (element i is the capture at place i of the submission), each stage's
// array chained to the previous stage's element by element
// (`--dependency=aftercorr:<id> --kill-on-invalid-dep=yes`): a capture's next
// stage starts when its previous one succeeded, and is cancelled when it
// failed. `--array=0-N%K` runs at most K captures of a stage at once.
//
// It shells out to Slurm's commands from argument vectors (never a shell
// line): sbatch --parsable to submit, squeue and scontrol with plain format
// strings (not --json, whose shape changes between Slurm versions) to look at
// the jobs (squeue --me: look from the account that submitted). Slurm's
// states only say whether a job is still queued or running;
// the result files decide whether it succeeded (batch/batch.h).
//
// Each stage's job script, <run dir>/<stage>.sbatch, lists the captures and
// runs the stage for the element's one with the absolute path of the hairrig
// binary that submitted it, so the batch folder, the captures and that
// binary must be at the same paths on every node (a shared filesystem).
// A job's cores are the stage's `threads` (--cpus-per-task); its --time and
// --mem are the submission's for that stage, when given.
#pragma once

#include <map>
#include <string>
#include <utility>

#include "batch/engine.h"

namespace hairrig {

// The programs the engine runs: looked up in PATH unless given with a '/'.
struct SlurmCommands {
  std::string sbatch = "sbatch";
  std::string squeue = "squeue";
  std::string scontrol = "scontrol";
  std::string scancel = "scancel";
};

class SlurmEngine : public BatchEngine {
 public:
  explicit SlurmEngine(SlurmCommands commands = {}) : commands_(std::move(commands)) {}
  // Writes the job scripts and submits the arrays in stage order; if one
  // sbatch fails, the arrays already submitted are cancelled (scancel) and
  // its error is returned. The batch folder's path must not contain '%'
  // (sbatch expands it in --output).
  Status Submit(const SubmitPlan& plan, Submission* submission,
                const std::function<Status()>& record) override;
  Result<JobViews> View(const Submission& submission) override;

 private:
  // Writes the stage's job script and submits its array; the array job id.
  Result<std::string> SubmitStage(const SubmitPlan& plan, const Submission& submission, Stage stage,
                                  const std::string& previous_job_id);

  SlurmCommands commands_;
};

// A job's state as squeue or scontrol print it.
struct SlurmJobState {
  std::string state;   // PENDING, RUNNING, COMPLETED, FAILED, CANCELLED, ...
  std::string reason;  // Dependency, DependencyNeverSatisfied, None, ...
};
// (array job id, array task id) -> state.
using SlurmArrayStates = std::map<std::pair<std::string, size_t>, SlurmJobState>;

// The job id `sbatch --parsable` prints ("1041", or "1041;cluster");
// CorruptData quoting the output otherwise.
Result<std::string> ParseSbatchJobId(const std::string& output);
// Lines of `squeue --noheader --array --format=%F|%K|%T|%r`; lines of other
// shapes (a job that is not an array element) are left out.
SlurmArrayStates ParseSqueueArrayStates(const std::string& output);
// Lines of `scontrol show job --oneliner`: their ArrayJobId, ArrayTaskId,
// JobState and Reason; lines without a single array task id are left out.
SlurmArrayStates ParseScontrolArrayStates(const std::string& output);
// Queued (PENDING, CONFIGURING, REQUEUED, SUSPENDED, ...), running (RUNNING,
// COMPLETING, ...), or ended (every other state).
JobPhase PhaseOfSlurmState(const std::string& state);

// The job script of one stage's array (bash, every value single-quoted).
std::string SlurmJobScript(const SubmitPlan& plan, const Submission& submission, Stage stage);
// sbatch's arguments after the program name, for the stage's array chained
// to `previous_job_id` ("" for the first stage).
std::vector<std::string> SbatchArguments(const SubmitPlan& plan, const Submission& submission,
                                         Stage stage, const std::string& script_path,
                                         const std::string& previous_job_id);

}  // namespace hairrig
