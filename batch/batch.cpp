#include "batch/batch.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <system_error>
#include <thread>

#include "batch/engine.h"
#include "batch/stage_record.h"
#include "core/file_util.h"
#include "core/log.h"
#include "rig/capture_dataset.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr int kDefaultMaxParallel = 2;
constexpr const char* kStates[] = {"done", "skipped", "failed", "blocked", "pending", "running"};

std::string AbsoluteFolder(const std::string& dir) {
  return fs::absolute(dir).lexically_normal().string();
}

// Entries "VALUE" (every stage) or "STAGE=VALUE" over `values`.
Status ApplyPerStage(const std::vector<std::string>& entries, const char* option,
                     std::map<std::string, std::string>* values) {
  for (const std::string& entry : entries) {
    const size_t equals = entry.find('=');
    const std::string key = equals == std::string::npos ? "*" : entry.substr(0, equals);
    const std::string value = equals == std::string::npos ? entry : entry.substr(equals + 1);
    if (key != "*") HR_RETURN_IF_ERROR(ParseStage(key).status().WithContext(option));
    if (value.empty()) return InvalidArgument(std::string(option) + " '" + entry + "': no value");
    (*values)[key] = value;
  }
  return Status::Ok();
}

Result<StageSettings> SubmissionSettings(const std::string& batch_dir, const SubmitOptions& o,
                                         const Submission* latest) {
  if (!o.stage_options.empty()) return LoadStageSettings(o.stage_options);
  if (latest != nullptr) return LoadStageSettings(latest->OptionsFile(batch_dir));
  return StageSettings{};
}

// The new submission of `captures`: `o`'s settings over the batch's latest submission's.
Result<Submission> NewSubmission(const BatchState& state, const std::vector<size_t>& captures,
                                 const SubmitOptions& o) {
  const Submission* latest = state.submissions.empty() ? nullptr : &state.submissions.back();
  Submission s;
  s.run_id = NewRunId(state.submissions.size() + 1);
  s.engine = o.engine ? *o.engine : latest ? latest->engine : EngineKind::kLocal;
  s.stages = !o.stages.empty() ? o.stages
             : latest          ? latest->stages
                               : std::vector<Stage>(kAllStages.begin(), kAllStages.end());
  s.captures = captures;
  s.submitted_utc = UtcNow();
  s.max_parallel = o.max_parallel ? *o.max_parallel
                   : latest       ? latest->max_parallel
                                  : kDefaultMaxParallel;
  if (s.max_parallel < 0) return InvalidArgument("--max-parallel must be 0 (no limit) or more");
  s.partition = o.partition ? *o.partition : latest ? latest->partition : "";
  if (latest != nullptr) {
    s.time_limit = latest->time_limit;
    s.mem = latest->mem;
  }
  HR_RETURN_IF_ERROR(ApplyPerStage(o.time_limit, "--time", &s.time_limit));
  HR_RETURN_IF_ERROR(ApplyPerStage(o.mem, "--mem", &s.mem));
  return s;
}

// Runs one new submission of `captures` with the batch folder locked.
Result<SubmitSummary> SubmitLocked(const std::string& batch_dir, BatchState state,
                                   const std::vector<size_t>& captures, const SubmitOptions& o) {
  if (o.hairrig_exe.empty())
    return InvalidArgument("the hairrig binary's path is needed for the jobs");
  HR_ASSIGN_OR_RETURN(Submission submission, NewSubmission(state, captures, o));
  const Submission* latest = state.submissions.empty() ? nullptr : &state.submissions.back();
  HR_ASSIGN_OR_RETURN(const StageSettings settings, SubmissionSettings(batch_dir, o, latest));

  SubmitPlan plan;
  plan.batch_dir = batch_dir;
  plan.hairrig_exe = o.hairrig_exe;
  plan.settings = settings;
  for (size_t c : captures) plan.capture_dirs.push_back(state.captures[c]);
  std::error_code ec;
  fs::create_directories(submission.RunDir(batch_dir), ec);
  if (ec) return IoError(submission.RunDir(batch_dir) + ": cannot create (" + ec.message() + ")");
  HR_RETURN_IF_ERROR(
      WriteFileAtomic(submission.OptionsFile(batch_dir), settings.ToJson().dump(2) + "\n"));

  state.submissions.push_back(std::move(submission));
  Submission* added = &state.submissions.back();
  const std::unique_ptr<BatchEngine> engine = MakeBatchEngine(added->engine);
  HR_RETURN_IF_ERROR(
      engine->Submit(plan, added, [&] { return WriteBatchState(batch_dir, state); }));

  SubmitSummary summary;
  summary.batch_dir = batch_dir;
  summary.run_id = added->run_id;
  summary.engine = added->engine;
  summary.stages = added->stages;
  summary.captures = plan.capture_dirs;
  summary.job_ids = added->job_ids;
  // The submission stands even when its jobs cannot be looked at just now.
  Result<BatchReport> report = ReportBatch(batch_dir);
  if (report.ok()) {
    summary.report = *std::move(report);
  } else {
    LogWarning("submitted, but the batch's state cannot be read now: " +
               report.status().ToString());
    summary.report.batch_dir = batch_dir;
  }
  return summary;
}

Result<BatchState> StartOrReadBatch(const std::string& batch_dir,
                                    const std::string& captures_source) {
  Result<BatchState> read = ReadBatchState(batch_dir);
  if (!read.ok() && read.status().code() != StatusCode::kNotFound) return read.status();
  if (read.ok()) {
    if (!captures_source.empty()) {
      HR_ASSIGN_OR_RETURN(const std::vector<std::string> captures, FindCaptures(captures_source));
      if (captures != read->captures) {
        return InvalidArgument(batch_dir + " holds a batch of other captures than " +
                               captures_source + ": start a new batch in another --batch folder");
      }
    }
    return read;
  }
  if (captures_source.empty()) {
    return InvalidArgument(batch_dir +
                           " holds no batch yet: give its captures with --captures FILE_OR_FOLDER");
  }
  BatchState state;
  state.created_utc = UtcNow();
  HR_ASSIGN_OR_RETURN(state.captures, FindCaptures(captures_source));
  return state;
}

// The states of a submission's captures' stages as its engine sees them, asked once per submission.
class EngineViews {
 public:
  Result<const JobViews*> For(const Submission& submission) {
    auto it = views_.find(submission.run_id);
    if (it == views_.end()) {
      HR_ASSIGN_OR_RETURN(JobViews views, MakeBatchEngine(submission.engine)->View(submission));
      it = views_.emplace(submission.run_id, std::move(views)).first;
    }
    return &it->second;
  }

 private:
  std::map<std::string, JobViews> views_;
};

// One cell from the stage's result file and the engine's view of its job.
StageCell DecideCell(const std::string& capture, Stage stage, const Submission& submission,
                     const JobView& view, const std::string& blocked_by) {
  StageCell cell;
  cell.run_id = submission.run_id;
  const Result<StageRecord> record = ReadStageRecord(capture, stage);
  const std::string engine_words = view.detail.empty() ? "" : " (" + view.detail + ")";
  if (record.ok() && record->run_id == submission.run_id) {
    cell.input_hash = record->input_hash;
    cell.seconds = record->seconds;
    if (record->status == "ok") {
      cell.state = record->skipped ? "skipped" : "done";
    } else if (record->status == "failed") {
      cell.state = "failed";
      cell.error = record->error;
    } else if (view.phase != JobPhase::kEnded) {
      cell.state = "running";
    } else {
      cell.state = "failed";
      cell.error = "the stage started but never finished (killed, out of time or out of memory?)" +
                   engine_words;
    }
    return cell;
  }
  if (!blocked_by.empty()) {
    cell.state = "blocked";
    cell.error = "blocked: " + blocked_by + " did not succeed";
  } else if (view.phase == JobPhase::kQueued) {
    cell.state = "pending";
  } else if (view.phase == JobPhase::kRunning) {
    cell.state = "running";
  } else {
    cell.state = "failed";
    cell.error = "the job ended without writing its result" + engine_words;
    if (!record.ok() && record.status().code() != StatusCode::kNotFound)
      cell.error += ": " + record.status().message();
  }
  return cell;
}

// The earliest stage of `submission` before `stage` whose cell (of this
// submission) failed or was blocked; "" when none.
std::string BlockingStage(const Submission& submission, Stage stage,
                          const std::map<Stage, StageCell>& cells) {
  for (Stage earlier : submission.stages) {
    if (earlier == stage) break;
    const auto it = cells.find(earlier);
    if (it == cells.end() || it->second.run_id != submission.run_id) continue;
    if (it->second.state == "failed" || it->second.state == "blocked") return StageName(earlier);
  }
  return "";
}

Result<BatchReport> BuildReport(const std::string& batch_dir, const BatchState& state) {
  BatchReport report;
  report.batch_dir = batch_dir;
  for (Stage stage : kAllStages) {
    if (std::any_of(state.submissions.begin(), state.submissions.end(),
                    [&](const Submission& s) { return s.Holds(stage); })) {
      report.stages.push_back(stage);
    }
  }
  EngineViews engines;
  for (size_t c = 0; c < state.captures.size(); ++c) {
    CaptureReport row;
    row.capture = state.captures[c];
    std::map<Stage, StageCell> cells;
    for (Stage stage : report.stages) {
      const Submission* submission = state.LatestFor(c, stage);
      StageCell cell;
      if (submission != nullptr) {
        const size_t index = static_cast<size_t>(submission->IndexOf(c));
        HR_ASSIGN_OR_RETURN(const JobViews* views, engines.For(*submission));
        cell = DecideCell(row.capture, stage, *submission, views->Get(stage, index),
                          BlockingStage(*submission, stage, cells));
        cell.log = submission->LogFile(batch_dir, stage, index);
      }
      cells[stage] = cell;
      row.stages.push_back(cell);
    }
    report.captures.push_back(std::move(row));
  }
  return report;
}

// The folder every capture lies in ("" when they share none but the root).
fs::path CommonFolder(const std::vector<CaptureReport>& captures) {
  if (captures.empty()) return {};
  fs::path common = fs::path(captures.front().capture).parent_path();
  for (const CaptureReport& c : captures) {
    while (!common.empty() && common != common.root_path() &&
           fs::path(c.capture).lexically_relative(common).string().rfind("..", 0) == 0) {
      common = common.parent_path();
    }
  }
  return common == common.root_path() ? fs::path() : common;
}

}  // namespace

int BatchReport::Count(const std::string& state) const {
  int count = 0;
  for (const CaptureReport& c : captures) {
    for (const StageCell& cell : c.stages) count += cell.state == state;
  }
  return count;
}

bool BatchReport::Finished() const { return Count("pending") == 0 && Count("running") == 0; }

bool BatchReport::AllSucceeded() const {
  for (const CaptureReport& c : captures) {
    for (const StageCell& cell : c.stages) {
      if (!cell.state.empty() && cell.state != "done" && cell.state != "skipped") return false;
    }
  }
  return true;
}

nlohmann::json BatchReport::ToJson() const {
  nlohmann::json stage_names = nlohmann::json::array();
  for (Stage stage : stages) stage_names.push_back(StageName(stage));
  nlohmann::json counts = nlohmann::json::object();
  for (const char* state : kStates) counts[state] = Count(state);
  nlohmann::json rows = nlohmann::json::array();
  for (const CaptureReport& c : captures) {
    nlohmann::json cells = nlohmann::json::object();
    for (size_t k = 0; k < stages.size(); ++k) {
      const StageCell& cell = c.stages[k];
      cells[StageName(stages[k])] = {{"state", cell.state.empty() ? "not submitted" : cell.state},
                                     {"error", cell.error},
                                     {"run_id", cell.run_id},
                                     {"input_hash", cell.input_hash},
                                     {"seconds", cell.seconds},
                                     {"log", cell.log}};
    }
    rows.push_back({{"capture", c.capture}, {"stages", cells}});
  }
  return {{"batch", batch_dir},     {"stages", stage_names},
          {"finished", Finished()}, {"all_succeeded", AllSucceeded()},
          {"counts", counts},       {"captures", rows},
          {"brief", BriefReport()}};
}

std::string BatchReport::Table() const {
  const fs::path common = CommonFolder(captures);
  std::vector<std::string> names;
  size_t width = std::string("capture").size();
  for (const CaptureReport& c : captures) {
    names.push_back(common.empty() ? c.capture
                                   : fs::path(c.capture).lexically_relative(common).string());
    width = std::max(width, names.back().size());
  }
  std::string text = common.empty() ? "" : "captures in " + common.string() + "\n";
  auto pad = [](const std::string& s, size_t n) {
    return s + std::string(n > s.size() ? n - s.size() : 0, ' ');
  };
  text += pad("capture", width);
  for (Stage stage : stages) text += "  " + pad(StageName(stage), 12);
  text += "\n";
  std::string failures;
  for (size_t r = 0; r < captures.size(); ++r) {
    text += pad(names[r], width);
    for (size_t k = 0; k < stages.size(); ++k) {
      const StageCell& cell = captures[r].stages[k];
      text += "  " + pad(cell.state.empty() ? "-" : cell.state, 12);
      if (cell.state == "failed") {
        failures += "  " + names[r] + " " + StageName(stages[k]) + ": " + cell.error +
                    "\n    log: " + cell.log + "\n";
      }
    }
    text += "\n";
  }
  if (!failures.empty()) text += "failed:\n" + failures;
  return text + BriefReport() + "\n";
}

std::string BatchReport::BriefReport() const {
  std::string text =
      std::to_string(captures.size()) + " captures x " + std::to_string(stages.size()) + " stages:";
  bool first = true;
  for (const char* state : kStates) {
    const int n = Count(state);
    if (n == 0) continue;
    text += (first ? " " : ", ") + std::to_string(n) + " " + state;
    first = false;
  }
  if (first) text += " nothing submitted";
  return text + (Finished() ? "" : " (in progress)");
}

nlohmann::json SubmitSummary::ToJson() const {
  nlohmann::json stage_names = nlohmann::json::array();
  for (Stage stage : stages) stage_names.push_back(StageName(stage));
  return {{"batch", batch_dir},       {"run_id", run_id},     {"engine", EngineName(engine)},
          {"stages", stage_names},    {"captures", captures}, {"job_ids", job_ids},
          {"report", report.ToJson()}};
}

Status SubmitOptions::Check() const {
  if (batch_dir.empty()) return InvalidArgument("batch_dir (the batch folder) is required");
  if (max_parallel && *max_parallel < 0)
    return InvalidArgument("--max-parallel must be 0 (no limit) or more");
  if (hairrig_exe.empty())
    return InvalidArgument("the hairrig binary's path is needed for the jobs");
  return Status::Ok();
}

Result<SubmitSummary> SubmitBatch(const SubmitOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string batch_dir = AbsoluteFolder(options.batch_dir);
  std::error_code ec;
  fs::create_directories(batch_dir, ec);
  if (ec) return IoError(batch_dir + ": cannot create the batch folder (" + ec.message() + ")");
  HR_ASSIGN_OR_RETURN(const BatchLock lock, BatchLock::Acquire(batch_dir));
  HR_ASSIGN_OR_RETURN(BatchState state, StartOrReadBatch(batch_dir, options.captures));
  std::vector<size_t> all(state.captures.size());
  for (size_t c = 0; c < all.size(); ++c) all[c] = c;
  return SubmitLocked(batch_dir, std::move(state), all, options);
}

Result<SubmitSummary> ResubmitFailed(const SubmitOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string batch_dir = AbsoluteFolder(options.batch_dir);
  HR_RETURN_IF_ERROR(ReadBatchState(batch_dir).status());  // names a folder without a batch
  HR_ASSIGN_OR_RETURN(const BatchLock lock, BatchLock::Acquire(batch_dir));
  HR_ASSIGN_OR_RETURN(BatchState state, ReadBatchState(batch_dir));
  HR_ASSIGN_OR_RETURN(const BatchReport report, BuildReport(batch_dir, state));
  std::vector<size_t> failed;
  for (size_t c = 0; c < report.captures.size(); ++c) {
    const auto& cells = report.captures[c].stages;
    if (std::any_of(cells.begin(), cells.end(), [](const StageCell& cell) {
          return cell.state == "failed" || cell.state == "blocked";
        })) {
      failed.push_back(c);
    }
  }
  if (failed.empty()) {
    SubmitSummary nothing;
    nothing.batch_dir = batch_dir;
    nothing.report = report;
    return nothing;
  }
  return SubmitLocked(batch_dir, std::move(state), failed, options);
}

Result<BatchReport> ReportBatch(const std::string& batch_dir) {
  const std::string dir = AbsoluteFolder(batch_dir);
  HR_ASSIGN_OR_RETURN(const BatchState state, ReadBatchState(dir));
  return BuildReport(dir, state);
}

Result<BatchReport> WaitForBatch(const std::string& batch_dir, double timeout_s, double poll_s) {
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    HR_ASSIGN_OR_RETURN(BatchReport report, ReportBatch(batch_dir));
    if (report.Finished()) return report;
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (timeout_s > 0 && waited >= timeout_s) {
      char text[64];
      std::snprintf(text, sizeof text, "%.0f s", waited);
      return Timeout(batch_dir + ": still running after " + text + ": " + report.BriefReport());
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.05, poll_s)));
  }
}

}  // namespace hairrig
