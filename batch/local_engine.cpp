#include "batch/local_engine.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <system_error>

#include "batch/process.h"
#include "batch/stage_record.h"
#include "core/log.h"
#include "core/parallel.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string ThisHost() {
  char name[256] = {};
  return ::gethostname(name, sizeof name - 1) == 0 ? name : "";
}

// Runs the capture's stages in order until one fails.
void RunCaptureStages(const SubmitPlan& plan, const Submission& submission, size_t index) {
  const std::string& capture = plan.capture_dirs[index];
  for (Stage stage : submission.stages) {
    const std::string log = submission.LogFile(plan.batch_dir, stage, index);
    std::vector<std::string> argv{plan.hairrig_exe};
    for (std::string& arg : StageJobArguments(plan, submission, stage, capture))
      argv.push_back(std::move(arg));
    ProcessOptions options;
    options.output_file = log;
    const Result<ProcessResult> run = RunProcess(argv, options);
    if (!run.ok()) {
      // The report finds no result for this run and points at the log.
      std::ofstream(log, std::ios::app) << "hairrig batch: " << run.status().ToString() << "\n";
      LogError(std::string(StageName(stage)) + " of " + capture + ": " + run.status().ToString());
      return;
    }
    if (run->exit_code != 0) {
      LogWarning(std::string(StageName(stage)) + " of " + capture + " failed (exit code " +
                 std::to_string(run->exit_code) + "; log: " + log + ")");
      return;
    }
    const Result<StageRecord> record = ReadStageRecord(capture, stage);
    if (!record.ok() || record->run_id != submission.run_id || !record->ok()) {
      LogWarning(std::string(StageName(stage)) + " of " + capture +
                 " ended without a successful result (log: " + log + ")");
      return;
    }
    LogInfo(std::string(StageName(stage)) + " of " + capture + ": done");
  }
}

}  // namespace

Status LocalEngine::Submit(const SubmitPlan& plan, Submission* submission,
                           const std::function<Status()>& record) {
  const fs::path logs = fs::path(submission->RunDir(plan.batch_dir)) / "logs";
  std::error_code ec;
  fs::create_directories(logs, ec);
  if (ec) return IoError(logs.string() + ": cannot create (" + ec.message() + ")");
  submission->runner_host = ThisHost();
  submission->runner_pid = ::getpid();
  submission->runner_start_ticks = ProcessStartTicks(::getpid());
  HR_RETURN_IF_ERROR(record());
  const size_t count = plan.capture_dirs.size();
  const int workers =
      submission->max_parallel > 0 ? submission->max_parallel : static_cast<int>(count);
  ParallelFor(count, workers,
              [&] { return [&](size_t index) { RunCaptureStages(plan, *submission, index); }; });
  submission->runner_pid = 0;  // ended: stages without a result now count as failed or blocked
  submission->runner_start_ticks = 0;
  return record();
}

Result<JobViews> LocalEngine::View(const Submission& submission) {
  JobViews views;
  const bool runs =
      submission.runner_pid > 0 && submission.runner_host == ThisHost() &&
      ProcessRuns(static_cast<pid_t>(submission.runner_pid), submission.runner_start_ticks);
  if (!runs) return views;
  for (Stage stage : submission.stages) {
    for (size_t index = 0; index < submission.captures.size(); ++index) {
      views.Set(
          stage, index,
          JobView{JobPhase::kQueued, "local runner pid " + std::to_string(submission.runner_pid)});
    }
  }
  return views;
}

}  // namespace hairrig
