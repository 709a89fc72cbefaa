#include "batch/stage_record.h"

#include <filesystem>
#include <system_error>

#include "core/file_util.h"
#include "core/json_file.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFormat = "hairrig-stage-result";
constexpr int kVersion = 1;

}  // namespace

nlohmann::json StageRecord::ToJson() const {
  nlohmann::json j{
      {"format", kFormat},        {"version", kVersion}, {"stage", stage},
      {"status", status},         {"skipped", skipped},  {"hairrig_version", hairrig_version},
      {"input_hash", input_hash}, {"inputs", inputs},    {"options", options},
      {"run_id", run_id},         {"host", host},        {"pid", pid},
      {"start_utc", start_utc},   {"end_utc", end_utc},  {"seconds", seconds},
      {"summary", summary}};
  if (!hairrig_build.empty()) j["hairrig_build"] = hairrig_build;
  if (!checked_utc.empty()) j["checked_utc"] = checked_utc;
  if (!error.empty()) j["error"] = error;
  if (injected_fault) j["injected_fault"] = true;
  return j;
}

std::string StageRecordPath(const std::string& capture_dir, Stage stage) {
  return (fs::path(capture_dir) / StageFolder(stage) / "result.json").string();
}

Result<StageRecord> ReadStageRecord(const std::string& capture_dir, Stage stage) {
  const std::string path = StageRecordPath(capture_dir, stage);
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(path + ": no result (the stage has not run)");
  HR_ASSIGN_OR_RETURN(const nlohmann::json j, ReadJsonFile(path));
  const JsonObject o(j, path);
  if (o.StringOr("format", "") != kFormat || o.IntegerOr("version", 0) != kVersion) {
    return CorruptData(path + ": not a hairrig stage result of version " +
                       std::to_string(kVersion));
  }
  StageRecord r;
  r.stage = o.String("stage");
  r.status = o.String("status");
  if (o.ok() && r.status != "ok" && r.status != "failed" && r.status != "running") {
    o.Fail("status", "'" + r.status + "' is not one of ok, failed, running");
  }
  r.skipped = o.BoolOr("skipped", false);
  r.injected_fault = o.BoolOr("injected_fault", false);
  r.hairrig_version = o.StringOr("hairrig_version", "");
  r.hairrig_build = o.StringOr("hairrig_build", "");
  r.input_hash = o.StringOr("input_hash", "");
  r.inputs = o.Raw("inputs").is_object() ? o.Raw("inputs") : nlohmann::json::object();
  r.options = o.Raw("options").is_object() ? o.Raw("options") : nlohmann::json::object();
  r.run_id = o.StringOr("run_id", "");
  r.host = o.StringOr("host", "");
  r.pid = o.IntegerOr("pid", 0);
  r.start_utc = o.StringOr("start_utc", "");
  r.end_utc = o.StringOr("end_utc", "");
  r.checked_utc = o.StringOr("checked_utc", "");
  r.seconds = o.NumberOr("seconds", 0);
  r.error = o.StringOr("error", "");
  r.summary = o.Raw("summary").is_object() ? o.Raw("summary") : nlohmann::json::object();
  HR_RETURN_IF_ERROR(o.status());
  if (r.stage != StageName(stage)) {
    return CorruptData(path + ": field 'stage': '" + r.stage + "', expected '" + StageName(stage) +
                       "'");
  }
  return r;
}

Status WriteStageRecord(const std::string& capture_dir, Stage stage, const StageRecord& record) {
  const std::string path = StageRecordPath(capture_dir, stage);
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  if (ec)
    return IoError(fs::path(path).parent_path().string() + ": cannot create (" + ec.message() +
                   ")");
  return WriteFileAtomic(path, record.ToJson().dump(2) + "\n");
}

}  // namespace hairrig
