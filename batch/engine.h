// How a batch's stage jobs run: the local engine (batch/local_engine.h, the
// default) or Slurm (batch/slurm_engine.h). Every job is the same command,
// `hairrig stage <name> --capture DIR --options FILE --run-id ID`
// (batch/stage.h); the result files it writes, not the engine, decide
// whether it succeeded (batch/batch.h).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "batch/batch_state.h"
#include "batch/stages.h"
#include "core/status.h"

namespace hairrig {

// What the engine says of one job: queued, running, or ended (or unknown to it).
enum class JobPhase { kQueued, kRunning, kEnded };

struct JobView {
  JobPhase phase = JobPhase::kEnded;
  // The engine's own words, for reports ("Slurm: CANCELLED (DependencyNeverSatisfied)").
  std::string detail;
};

// The engine's view of a submission's jobs, by stage and the capture's place
// in the submission; a job it does not list has ended.
class JobViews {
 public:
  void Set(Stage stage, size_t index, JobView view) { views_[{stage, index}] = std::move(view); }
  JobView Get(Stage stage, size_t index) const {
    const auto it = views_.find({stage, index});
    return it == views_.end() ? JobView{} : it->second;
  }

 private:
  std::map<std::pair<Stage, size_t>, JobView> views_;
};

// One submission to run: its record (run id, stages, captures, limits) and
// what its jobs need.
struct SubmitPlan {
  std::string batch_dir;
  std::string hairrig_exe;                // the absolute path every job runs
  std::vector<std::string> capture_dirs;  // the submission's captures, in its order
  StageSettings settings;                 // as written to the submission's options file
};

// The job of one stage of one capture: hairrig's arguments after the binary.
std::vector<std::string> StageJobArguments(const SubmitPlan& plan, const Submission& submission,
                                           Stage stage, const std::string& capture_dir);

class BatchEngine {
 public:
  virtual ~BatchEngine() = default;
  // Starts the submission's jobs. `record` saves the submission (with its job
  // ids or runner filled in) in the batch folder; the engine calls it as soon
  // as the jobs can be looked up (the local engine again when they ended),
  // and fails if it fails.
  virtual Status Submit(const SubmitPlan& plan, Submission* submission,
                        const std::function<Status()>& record) = 0;
  // The engine's view of the submission's jobs. Errors: the engine cannot be
  // asked (Slurm's commands missing or failing).
  virtual Result<JobViews> View(const Submission& submission) = 0;
};

std::unique_ptr<BatchEngine> MakeBatchEngine(EngineKind kind);

}  // namespace hairrig
