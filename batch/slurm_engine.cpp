#include "batch/slurm_engine.h"

#include <cctype>
#include <filesystem>
#include <set>
#include <sstream>
#include <system_error>

#include "batch/process.h"
#include "core/file_util.h"
#include "core/log.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// Stands for the element's capture in StageJobArguments, replaced by a
// shell expression in the job script.
constexpr const char* kCapturePlaceholder = "\001capture\001";

std::string Trim(const std::string& text) {
  const size_t start = text.find_first_not_of(" \t\r\n");
  if (start == std::string::npos) return "";
  const size_t end = text.find_last_not_of(" \t\r\n");
  return text.substr(start, end + 1 - start);
}

bool AllDigits(const std::string& text) {
  if (text.empty()) return false;
  for (unsigned char c : text) {
    if (!std::isdigit(c)) return false;
  }
  return true;
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, separator);) parts.push_back(part);
  return parts;
}

void AddState(const std::string& array_id, const std::string& task_id, SlurmJobState state,
              SlurmArrayStates* states) {
  if (!AllDigits(array_id) || !AllDigits(task_id)) return;
  (*states)[{array_id, std::stoul(task_id)}] = std::move(state);
}

Status Cancel(const SlurmCommands& commands, const std::vector<std::string>& job_ids) {
  if (job_ids.empty()) return Status::Ok();
  std::vector<std::string> argv{commands.scancel};
  argv.insert(argv.end(), job_ids.begin(), job_ids.end());
  HR_ASSIGN_OR_RETURN(const ProcessResult run, RunProcess(argv));
  if (run.exit_code != 0)
    return Unavailable("scancel " + job_ids.front() + " ...: " + run.Describe());
  return Status::Ok();
}

Status WriteJobScript(const std::string& path, const std::string& text) {
  HR_RETURN_IF_ERROR(WriteFileAtomic(path, text));
  std::error_code ec;
  fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add, ec);
  return Status::Ok();
}

}  // namespace

Result<std::string> ParseSbatchJobId(const std::string& output) {
  const std::string line = Trim(output.substr(0, output.find('\n')));
  const std::string id = line.substr(0, line.find(';'));
  if (!AllDigits(id))
    return CorruptData("sbatch --parsable printed '" + Trim(output) + "', not a job id");
  return id;
}

SlurmArrayStates ParseSqueueArrayStates(const std::string& output) {
  SlurmArrayStates states;
  for (const std::string& line : Split(output, '\n')) {
    const std::vector<std::string> fields = Split(Trim(line), '|');
    if (fields.size() < 3) continue;
    AddState(fields[0], fields[1], {fields[2], fields.size() > 3 ? fields[3] : ""}, &states);
  }
  return states;
}

SlurmArrayStates ParseScontrolArrayStates(const std::string& output) {
  SlurmArrayStates states;
  for (const std::string& line : Split(output, '\n')) {
    std::map<std::string, std::string> fields;
    std::istringstream words(line);
    for (std::string word; words >> word;) {
      const size_t equals = word.find('=');
      if (equals != std::string::npos)
        fields.emplace(word.substr(0, equals), word.substr(equals + 1));
    }
    AddState(fields["ArrayJobId"], fields["ArrayTaskId"], {fields["JobState"], fields["Reason"]},
             &states);
  }
  return states;
}

JobPhase PhaseOfSlurmState(const std::string& state) {
  static const std::set<std::string> kQueued = {"PENDING",      "CONFIGURING", "REQUEUED",
                                                "REQUEUE_HOLD", "REQUEUE_FED", "RESIZING",
                                                "SUSPENDED",    "STOPPED"};
  static const std::set<std::string> kRunning = {"RUNNING", "COMPLETING", "SIGNALING", "STAGE_OUT"};
  if (kQueued.count(state) > 0) return JobPhase::kQueued;
  if (kRunning.count(state) > 0) return JobPhase::kRunning;
  return JobPhase::kEnded;
}

std::string SlurmJobScript(const SubmitPlan& plan, const Submission& submission, Stage stage) {
  std::string script = "#!/bin/bash\n";
  script += "# hairrig batch submission " + submission.run_id + ": the " + StageName(stage) +
            " stage;\n# element i of the job array runs it on captures[i].\n";
  script += "captures=(\n";
  for (const std::string& capture : plan.capture_dirs) script += "  " + ShellQuote(capture) + "\n";
  script += ")\nexec " + ShellQuote(plan.hairrig_exe);
  for (const std::string& arg : StageJobArguments(plan, submission, stage, kCapturePlaceholder)) {
    script += ' ';
    script += arg == kCapturePlaceholder ? std::string("\"${captures[$SLURM_ARRAY_TASK_ID]}\"")
                                         : ShellQuote(arg);
  }
  return script + "\n";
}

std::vector<std::string> SbatchArguments(const SubmitPlan& plan, const Submission& submission,
                                         Stage stage, const std::string& script_path,
                                         const std::string& previous_job_id) {
  const std::string last = std::to_string(plan.capture_dirs.size() - 1);
  std::string array = "--array=0-" + last;
  if (submission.max_parallel > 0) array += "%" + std::to_string(submission.max_parallel);
  const std::string logs = (fs::path(submission.RunDir(plan.batch_dir)) / "logs").string();
  std::vector<std::string> args{"--parsable",
                                array,
                                "--job-name=hairrig-" + std::string(StageName(stage)),
                                "--output=" + logs + "/" + StageName(stage) + "_%a.log",
                                "--chdir=" + submission.RunDir(plan.batch_dir),
                                "--cpus-per-task=" + std::to_string(plan.settings.Threads(stage))};
  if (!submission.partition.empty()) args.push_back("--partition=" + submission.partition);
  const std::string time_limit = Submission::ForStage(submission.time_limit, stage);
  if (!time_limit.empty()) args.push_back("--time=" + time_limit);
  const std::string mem = Submission::ForStage(submission.mem, stage);
  if (!mem.empty()) args.push_back("--mem=" + mem);
  if (!previous_job_id.empty()) {
    args.push_back("--dependency=aftercorr:" + previous_job_id);
    args.push_back("--kill-on-invalid-dep=yes");
  }
  args.push_back(script_path);
  return args;
}

Status SlurmEngine::Submit(const SubmitPlan& plan, Submission* submission,
                           const std::function<Status()>& record) {
  if (plan.batch_dir.find('%') != std::string::npos) {
    return InvalidArgument(plan.batch_dir +
                           ": a batch folder for Slurm must not have '%' in its path "
                           "(sbatch expands it in log file names)");
  }
  const fs::path logs = fs::path(submission->RunDir(plan.batch_dir)) / "logs";
  std::error_code ec;
  fs::create_directories(logs, ec);
  if (ec) return IoError(logs.string() + ": cannot create (" + ec.message() + ")");
  std::vector<std::string> submitted;
  for (Stage stage : submission->stages) {
    const std::string previous = submitted.empty() ? "" : submitted.back();
    const Result<std::string> id = SubmitStage(plan, *submission, stage, previous);
    if (!id.ok()) {
      const Status cancelled = Cancel(commands_, submitted);
      if (!cancelled.ok())
        LogError("cancelling the arrays already submitted: " + cancelled.ToString());
      return id.status();
    }
    submission->job_ids[StageName(stage)] = *id;
    submitted.push_back(*id);
  }
  return record();
}

Result<std::string> SlurmEngine::SubmitStage(const SubmitPlan& plan, const Submission& submission,
                                             Stage stage, const std::string& previous_job_id) {
  const std::string script =
      (fs::path(submission.RunDir(plan.batch_dir)) / StageName(stage)).string() + ".sbatch";
  HR_RETURN_IF_ERROR(WriteJobScript(script, SlurmJobScript(plan, submission, stage)));
  std::vector<std::string> argv{commands_.sbatch};
  for (std::string& arg : SbatchArguments(plan, submission, stage, script, previous_job_id)) {
    argv.push_back(std::move(arg));
  }
  HR_ASSIGN_OR_RETURN(const ProcessResult run, RunProcess(argv));
  if (run.exit_code != 0) return Unavailable("sbatch " + script + ": " + run.Describe());
  return ParseSbatchJobId(run.out);
}

Result<JobViews> SlurmEngine::View(const Submission& submission) {
  HR_ASSIGN_OR_RETURN(
      const ProcessResult queue,
      RunProcess({commands_.squeue, "--noheader", "--array", "--me", "--format=%F|%K|%T|%r"}));
  if (queue.exit_code != 0) return Unavailable("squeue: " + queue.Describe());
  const SlurmArrayStates queued = ParseSqueueArrayStates(queue.out);
  std::set<std::string> gone_arrays;  // arrays with an element squeue no longer lists
  for (const auto& [stage_name, id] : submission.job_ids) {
    for (size_t index = 0; index < submission.captures.size(); ++index) {
      if (queued.count({id, index}) == 0) gone_arrays.insert(id);
    }
  }
  // Ended jobs stay known to scontrol for a while (MinJobAge); their state
  // explains a job that ended without a result. Unknown ids are not an error.
  SlurmArrayStates ended;
  for (const std::string& id : gone_arrays) {
    const Result<ProcessResult> shown =
        RunProcess({commands_.scontrol, "show", "job", "--oneliner", id});
    if (shown.ok() && shown->exit_code == 0) ended.merge(ParseScontrolArrayStates(shown->out));
  }
  JobViews views;
  for (const auto& [stage_name, id] : submission.job_ids) {
    const Result<Stage> stage = ParseStage(stage_name);
    if (!stage.ok()) continue;
    for (size_t index = 0; index < submission.captures.size(); ++index) {
      const auto in_queue = queued.find({id, index});
      const auto in_history = ended.find({id, index});
      const bool listed = in_queue != queued.end();
      if (!listed && in_history == ended.end()) continue;
      const SlurmJobState& s = listed ? in_queue->second : in_history->second;
      views.Set(*stage, index,
                {listed ? PhaseOfSlurmState(s.state) : JobPhase::kEnded,
                 "Slurm job " + id + "_" + std::to_string(index) + ": " + s.state +
                     (s.reason.empty() || s.reason == "None" ? "" : " (" + s.reason + ")")});
    }
  }
  return views;
}

}  // namespace hairrig
