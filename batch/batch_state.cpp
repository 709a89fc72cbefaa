#include "batch/batch_state.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <system_error>

#include "core/file_util.h"
#include "core/json_file.h"
#include "rig/capture_dataset.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFormat = "hairrig-batch";
constexpr int kVersion = 1;

std::string StatePath(const std::string& batch_dir) {
  return (fs::path(batch_dir) / "batch.json").string();
}

nlohmann::json SubmissionToJson(const Submission& s) {
  nlohmann::json stages = nlohmann::json::array();
  for (Stage stage : s.stages) stages.push_back(StageName(stage));
  return nlohmann::json{
      {"run_id", s.run_id},
      {"engine", EngineName(s.engine)},
      {"stages", stages},
      {"captures", s.captures},
      {"submitted_utc", s.submitted_utc},
      {"max_parallel", s.max_parallel},
      {"partition", s.partition},
      {"time_limit", s.time_limit},
      {"mem", s.mem},
      {"job_ids", s.job_ids},
      {"runner",
       {{"host", s.runner_host}, {"pid", s.runner_pid}, {"start_ticks", s.runner_start_ticks}}}};
}

std::map<std::string, std::string> StringMap(const JsonObject& o, const char* key) {
  std::map<std::string, std::string> values;
  if (!o.Has(key)) return values;
  const JsonObject map = o.Object(key);
  for (const std::string& name : map.Keys()) values[name] = map.String(name);
  return values;
}

Submission SubmissionFromJson(const JsonObject& o, size_t capture_count) {
  Submission s;
  s.run_id = o.String("run_id");
  const Result<EngineKind> engine = ParseEngine(o.String("engine"));
  if (engine.ok()) {
    s.engine = *engine;
  } else if (o.ok()) {
    o.Fail("engine", engine.status().message());
  }
  const nlohmann::json& stages = o.Raw("stages");
  for (const nlohmann::json& name : stages.is_array() ? stages : nlohmann::json::array()) {
    const Result<Stage> stage = ParseStage(name.is_string() ? name.get<std::string>() : "");
    if (!stage.ok()) {
      o.Fail("stages", stage.status().message());
      break;
    }
    s.stages.push_back(*stage);
  }
  for (int64_t index :
       o.IntegersOr("captures", {.min = 0, .max = static_cast<int64_t>(capture_count) - 1})) {
    s.captures.push_back(static_cast<size_t>(index));
  }
  s.submitted_utc = o.StringOr("submitted_utc", "");
  s.max_parallel = static_cast<int>(o.IntegerOr("max_parallel", 0, {.min = 0, .max = 1000000}));
  s.partition = o.StringOr("partition", "");
  s.time_limit = StringMap(o, "time_limit");
  s.mem = StringMap(o, "mem");
  s.job_ids = StringMap(o, "job_ids");
  if (o.Has("runner")) {
    const JsonObject runner = o.Object("runner");
    s.runner_host = runner.StringOr("host", "");
    s.runner_pid = runner.IntegerOr("pid", 0);
    s.runner_start_ticks = static_cast<uint64_t>(runner.IntegerOr("start_ticks", 0, {.min = 0}));
  }
  return s;
}

// Capture folders under `dir`, not descending into a capture.
void SearchCaptures(const fs::path& dir, std::vector<std::string>* found) {
  if (IsCaptureFolder(dir.string())) {
    found->push_back(dir.string());
    return;
  }
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_directory(ec) && !entry.is_symlink(ec)) SearchCaptures(entry.path(), found);
  }
}

Result<std::vector<std::string>> ReadCaptureList(const std::string& list_file) {
  std::ifstream in(list_file);
  if (!in) return IoError(list_file + ": cannot read the list of captures");
  const fs::path base = fs::absolute(list_file).parent_path();
  std::vector<std::string> captures;
  int line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
      line.pop_back();
    const size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos || line[start] == '#') continue;
    const fs::path path = (base / line.substr(start)).lexically_normal();
    if (!IsCaptureFolder(path.string())) {
      return InvalidArgument(list_file + ":" + std::to_string(line_number) + ": " + path.string() +
                             " is not a capture folder (no journal.jsonl and capture.json)");
    }
    captures.push_back(path.string());
  }
  return captures;
}

}  // namespace

const char* EngineName(EngineKind engine) {
  return engine == EngineKind::kSlurm ? "slurm" : "local";
}

Result<EngineKind> ParseEngine(const std::string& name) {
  if (name == "local") return EngineKind::kLocal;
  if (name == "slurm") return EngineKind::kSlurm;
  return InvalidArgument("unknown engine '" + name + "' (engines: local, slurm)");
}

bool Submission::Holds(Stage stage) const {
  return std::find(stages.begin(), stages.end(), stage) != stages.end();
}

int Submission::IndexOf(size_t capture) const {
  const auto it = std::find(captures.begin(), captures.end(), capture);
  return it == captures.end() ? -1 : static_cast<int>(it - captures.begin());
}

std::string Submission::RunDir(const std::string& batch_dir) const {
  return (fs::path(batch_dir) / "runs" / run_id).string();
}

std::string Submission::OptionsFile(const std::string& batch_dir) const {
  return (fs::path(RunDir(batch_dir)) / "stage_options.json").string();
}

std::string Submission::LogFile(const std::string& batch_dir, Stage stage, size_t index) const {
  return (fs::path(RunDir(batch_dir)) / "logs" /
          (std::string(StageName(stage)) + "_" + std::to_string(index) + ".log"))
      .string();
}

std::string Submission::ForStage(const std::map<std::string, std::string>& values, Stage stage) {
  auto it = values.find(StageName(stage));
  if (it == values.end()) it = values.find("*");
  return it == values.end() ? "" : it->second;
}

const Submission* BatchState::LatestFor(size_t capture, Stage stage) const {
  for (auto it = submissions.rbegin(); it != submissions.rend(); ++it) {
    if (it->Holds(stage) && it->IndexOf(capture) >= 0) return &*it;
  }
  return nullptr;
}

Result<BatchState> ReadBatchState(const std::string& batch_dir) {
  const std::string path = StatePath(batch_dir);
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    return NotFound(
        batch_dir +
        " holds no batch (no batch.json): start one with `hairrig batch submit --captures`");
  }
  HR_ASSIGN_OR_RETURN(const nlohmann::json j, ReadJsonFile(path));
  const JsonObject o(j, path);
  if (o.StringOr("format", "") != kFormat || o.IntegerOr("version", 0) != kVersion) {
    return CorruptData(path + ": not a hairrig batch of version " + std::to_string(kVersion));
  }
  BatchState state;
  state.created_utc = o.StringOr("created_utc", "");
  const nlohmann::json& captures = o.Raw("captures");
  if (!captures.is_array()) o.Fail("captures", "expected a list of capture folders");
  for (const nlohmann::json& c : captures.is_array() ? captures : nlohmann::json::array()) {
    if (!c.is_string()) {
      o.Fail("captures", "expected a list of capture folders");
      break;
    }
    state.captures.push_back(c.get<std::string>());
  }
  for (const JsonObject& s : o.Objects("submissions")) {
    state.submissions.push_back(SubmissionFromJson(s, state.captures.size()));
  }
  HR_RETURN_IF_ERROR(o.status());
  return state;
}

Status WriteBatchState(const std::string& batch_dir, const BatchState& state) {
  nlohmann::json submissions = nlohmann::json::array();
  for (const Submission& s : state.submissions) submissions.push_back(SubmissionToJson(s));
  const nlohmann::json j{{"format", kFormat},
                         {"version", kVersion},
                         {"created_utc", state.created_utc},
                         {"captures", state.captures},
                         {"submissions", submissions}};
  return WriteFileAtomic(StatePath(batch_dir), j.dump(2) + "\n");
}

Result<BatchLock> BatchLock::Acquire(const std::string& batch_dir) {
  const std::string path = (fs::path(batch_dir) / "batch.lock").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return IoErrorFromErrno(path + ": cannot open", errno);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd);
    if (error == EWOULDBLOCK) {
      return FailedPrecondition(
          batch_dir + " is in use by another `hairrig batch` command (a submit still running?)");
    }
    return IoErrorFromErrno(path + ": cannot lock", error);
  }
  return BatchLock(fd);
}

BatchLock::BatchLock(BatchLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

BatchLock::~BatchLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

bool IsCaptureFolder(const std::string& dir) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(dir) / "journal.jsonl", ec) &&
         fs::is_regular_file(fs::path(dir) / "capture.json", ec);
}

Result<std::vector<std::string>> FindCaptures(const std::string& source) {
  std::error_code ec;
  if (!fs::exists(source, ec)) return NotFound(source + ": no such file or folder of captures");
  std::vector<std::string> captures;
  if (fs::is_directory(source, ec)) {
    SearchCaptures(fs::absolute(source).lexically_normal(), &captures);
    std::sort(captures.begin(), captures.end());
  } else {
    HR_ASSIGN_OR_RETURN(captures, ReadCaptureList(source));
  }
  std::set<std::string> seen;
  for (std::string& capture : captures) {
    if (!capture.empty() && capture.back() == '/') capture.pop_back();
    if (capture.find('\n') != std::string::npos) {
      return InvalidArgument(capture +
                             ": a capture path with a newline cannot be listed in a job script");
    }
    if (!seen.insert(capture).second)
      return InvalidArgument(source + ": " + capture + " is listed twice");
  }
  if (captures.empty()) {
    return InvalidArgument(
        source + ": no capture folder (a folder with journal.jsonl and capture.json) found");
  }
  return captures;
}

std::string NewRunId(size_t submission_number) {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char time_text[32];
  std::strftime(time_text, sizeof time_text, "%Y%m%dT%H%M%S", &tm);
  std::random_device random;
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, "%06x", static_cast<unsigned>(random() & 0xffffff));
  char id[96];
  std::snprintf(id, sizeof id, "r%zu-%s-%s", submission_number, time_text, suffix);
  return id;
}

}  // namespace hairrig
