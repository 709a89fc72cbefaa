#include "batch/stage.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <system_error>

#include "batch/simulate_stage.h"
#include "batch/stage_record.h"
#include "core/file_util.h"
#include "core/head_config.h"
#include "core/log.h"
#include "core/sha256.h"
#include "core/strand_io.h"
#include "core/version.h"
#include "rig/calibrate_capture.h"
#include "rig/capture_dataset.h"
#include "rig/manifest_frames.h"
#include "rig/reconstruct_capture.h"
#include "rig/reconstruction_input.h"
#include "rig/rig_config.h"
#include "simulation/helix_model.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStrandsFile = "reconstruction/strands/strands.ply";
constexpr const char* kModelFile = "fit/model.json";
// The fitted model names its strands relative to its own folder, so a capture
// folder can move (another mount point on a cluster node) and keep its model.
constexpr const char* kModelSource = "../reconstruction/strands/strands.ply";

using InputFiles = std::map<std::string, std::string>;

Status Require(const std::string& capture_dir, const std::string& name, const char* written_by,
               InputFiles* files) {
  const fs::path path = fs::path(capture_dir) / name;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    return FailedPrecondition(path.string() + " is missing: " + written_by);
  }
  (*files)[name] = path.string();
  return Status::Ok();
}

Status AddOptionFile(const std::string& key, const std::string& path, InputFiles* files) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return NotFound(path + " (the option '" + key + "'): no such file");
  (*files)[key] = path;
  return Status::Ok();
}

// The capture's own inputs: its rig config snapshot, manifest and frames. A
// frame leading outside the capture folder is not read (the stage leaves it
// out); a frames/ folder leading outside refuses the capture
// (rig/manifest_frames.h CheckFramesFolder).
Status AddCaptureFiles(const std::string& capture_dir, InputFiles* files) {
  const char* capture_made = "not a capture folder made by `hairrig capture`?";
  HR_RETURN_IF_ERROR(Require(capture_dir, "rig.yaml", capture_made, files));
  HR_RETURN_IF_ERROR(Require(capture_dir, "manifest.json", capture_made, files));
  const fs::path frames = fs::path(capture_dir) / "frames";
  std::error_code ec;
  if (!fs::is_directory(frames, ec))
    return FailedPrecondition(frames.string() + " is missing: " + capture_made);
  HR_RETURN_IF_ERROR(CheckFramesFolder(capture_dir));
  for (const fs::directory_entry& entry : fs::directory_iterator(frames, ec)) {
    if (entry.is_regular_file(ec) && ResolveInside(entry.path().string(), capture_dir).ok())
      (*files)["frames/" + entry.path().filename().string()] = entry.path().string();
  }
  if (ec) return IoError(frames.string() + ": cannot list (" + ec.message() + ")");
  return Status::Ok();
}

// The head file the capture's rig.yaml names ("head: heads/mannequin.yaml");
// without a head there, the one the reconstruct stage fitted
// (reconstruction/head.yaml, rig/reconstruction_input.h) if it exists; ""
// when the head is written inline, or absent and not fitted.
Result<std::string> CaptureHeadFile(const std::string& capture_dir) {
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(capture_dir));
  if (!config.root.Has("head")) {
    const std::string fitted = (fs::path(capture_dir) / "reconstruction" / "head.yaml").string();
    std::error_code ec;
    return fs::is_regular_file(fitted, ec) ? fitted : std::string();
  }
  if (!config.root.HasScalar("head")) return std::string();
  return ResolveBesideFile((fs::path(config.relative_to) / "rig.yaml").string(),
                           config.root.String("head"));
}

// The simulate stage's settings with its head and scene files resolved.
Result<SimulateSettings> ResolvedSimulateSettings(const std::string& capture_dir,
                                                  const SimulateSettings& s) {
  SimulateSettings resolved = s;
  if (resolved.head.empty()) {
    HR_ASSIGN_OR_RETURN(resolved.head, CaptureHeadFile(capture_dir));
  }
  if (resolved.scene.empty()) {
    HR_ASSIGN_OR_RETURN(resolved.scene, EtcPath("scenes/default.yaml"));
  }
  return resolved;
}

std::string HashText(const std::string& text) { return Sha256Hex(text.data(), text.size()); }

struct HashedInputs {
  nlohmann::json files = nlohmann::json::object();  // name -> SHA-256
  std::string input_hash;
};

Result<HashedInputs> HashInputs(const StageOptions& o) {
  HR_ASSIGN_OR_RETURN(const InputFiles files, StageInputFiles(o.stage, o.capture_dir, o.settings));
  HashedInputs hashed;
  for (const auto& [name, path] : files) {
    HR_ASSIGN_OR_RETURN(hashed.files[name], Sha256OfFile(path));
  }
  // The files options name count by their contents (inputs), not their paths.
  nlohmann::json options = o.settings.StageJson(o.stage);
  for (const char* key : {"threads", "intrinsics", "head", "scene"}) {
    if (options.value(key, nlohmann::json()) != kFittedHead)
      options.erase(key);  // "fit" is no file
  }
  HR_ASSIGN_OR_RETURN(const std::string build, HairrigBuildId());
  const nlohmann::json identity{{"hairrig_version", HairrigVersion()},
                                {"hairrig_build", build},
                                {"stage", StageName(o.stage)},
                                {"options", options},
                                {"inputs", hashed.files}};
  hashed.input_hash = HashText(identity.dump());
  return hashed;
}

// HAIRRIG_STAGE_FAULT's entry matching this stage and capture, or "".
std::string InjectedFault(Stage stage, const std::string& capture_dir) {
  const char* value = std::getenv(kStageFaultVariable);
  if (value == nullptr) return "";
  const std::string wanted = std::string(StageName(stage)) + ":" + CaptureName(capture_dir);
  std::istringstream entries(value);
  for (std::string entry; std::getline(entries, entry, ',');) {
    if (entry == wanted) return entry;
  }
  return "";
}

Result<nlohmann::json> RunCalibrate(const std::string& dir, const CalibrateSettings& s) {
  CalibrateFolderOptions options;
  options.calibration.mode =
      s.mode == "free" ? CalibrationMode::kFree : CalibrationMode::kTurntable;
  options.calibration.threads = s.threads;
  options.calibration.hard_prior = s.hard_prior;
  options.prior_files = s.intrinsics;
  HR_ASSIGN_OR_RETURN(const CalibratedFolder done, CalibrateCaptureFolder(dir, options));
  int solved = 0;
  for (const FrameCalibration& f : done.result.frames) solved += f.solved;
  const std::string report = done.out_dir + "/report/report.txt";
  if (done.verdict.level == CalibrationVerdict::Level::kFailed) {
    std::string reasons;
    for (const std::string& reason : done.verdict.reasons)
      reasons += (reasons.empty() ? "" : "; ") + reason;
    return FailedPrecondition("calibration failed: " + reasons + " (see " + report + ")");
  }
  return nlohmann::json{{"verdict", done.verdict.name()},     {"reasons", done.verdict.reasons},
                        {"views", done.result.frames.size()}, {"views_solved", solved},
                        {"rms_px", done.result.rms_px},       {"report", report}};
}

Result<nlohmann::json> RunReconstruct(const std::string& dir, const ReconstructSettings& s) {
  ReconstructCaptureOptions options;
  options.dir = dir;
  options.head_file = s.head;
  options.points.threads = s.threads;
  options.points.mvs.stride_px = s.stride_px;
  options.points.mvs.iterations = s.iterations;
  options.points.hull.voxel_mm = s.hull_voxel_mm;
  HR_ASSIGN_OR_RETURN(options.strands.method, ParseStrandMethod(s.method));
  options.strands.strands = s.strands;
  options.strands.threads = s.threads;
  options.progress = [](const std::string& step, int done, int total) {
    if (done == total) LogInfo("reconstruct: " + step + " done");
  };
  HR_ASSIGN_OR_RETURN(const ReconstructCaptureSummary summary, ReconstructCapture(options));
  return summary.ToJson();
}

Result<nlohmann::json> RunFit(const std::string& dir, const FitSettings& s) {
  const std::string strands_file = (fs::path(dir) / kStrandsFile).string();
  HR_ASSIGN_OR_RETURN(const StrandSet strands, ReadStrands(strands_file));
  if (static_cast<size_t>(s.guides) > strands.num_strands()) {
    return InvalidArgument("fit: guides " + std::to_string(s.guides) + " is more than the " +
                           std::to_string(strands.num_strands()) + " strands of " + strands_file);
  }
  FitOptions options;
  options.guides.num_guides = s.guides;
  options.fitting.target_mean_error_mm = s.target_error_mm;
  options.threads = s.threads;
  FitSummary summary;
  Result<HelixModel> fitted = FitHairModel(strands, options, &summary);
  if (!fitted.ok()) return fitted.status().WithContext(strands_file);
  HelixModel model = std::move(fitted).value();
  model.source = kModelSource;
  const std::string out = (fs::path(dir) / kModelFile).string();
  std::error_code ec;
  fs::create_directories(fs::path(out).parent_path(), ec);
  if (ec)
    return IoError(fs::path(out).parent_path().string() + ": cannot create (" + ec.message() + ")");
  HR_RETURN_IF_ERROR(WriteHelixModel(out, model, summary));
  return nlohmann::json{{"out", out},
                        {"strands", summary.strands},
                        {"guides", summary.guides},
                        {"guide_rms_mm", summary.guide_rms_mm},
                        {"mean_elements", summary.mean_elements},
                        {"mean_error_mm", summary.mean_error_mm},
                        {"max_error_mm", summary.max_error_mm},
                        {"wall_s", summary.wall_s}};
}

// The dynamics write into a fresh folder beside the final one, which then
// replaces simulation/<scenario>/: a failed run never leaves half a result
// under the final name.
Result<nlohmann::json> RunSimulate(const std::string& dir, const SimulateSettings& s,
                                   const std::string& exe) {
  const fs::path folder = fs::path(dir) / StageFolder(Stage::kSimulate);
  const fs::path out = folder / s.scenario;
  const fs::path partial = folder / ("." + s.scenario + ".partial");
  std::error_code ec;
  fs::remove_all(partial, ec);
  fs::create_directories(folder, ec);
  if (ec) return IoError(folder.string() + ": cannot create (" + ec.message() + ")");
  // Absolute: the dynamics run in the model's folder.
  SimulateStageRequest request;
  request.model = fs::absolute(fs::path(dir) / kModelFile).string();
  request.out_dir = fs::absolute(partial).string();
  HR_ASSIGN_OR_RETURN(request.settings, ResolvedSimulateSettings(dir, s));
  for (std::string* file : {&request.settings.head, &request.settings.scene}) {
    if (!file->empty()) *file = fs::absolute(*file).string();
  }
  request.hairrig_exe = exe;
  HR_ASSIGN_OR_RETURN(nlohmann::json summary, RunSimulateForStage(request));
  fs::remove_all(out, ec);
  fs::rename(partial, out, ec);
  if (ec)
    return IoError(partial.string() + ": cannot rename to " + out.string() + " (" + ec.message() +
                   ")");
  summary["out"] = out.string();
  return summary;
}

Result<nlohmann::json> RunStageWork(const StageOptions& o) {
  switch (o.stage) {
    case Stage::kCalibrate:
      return RunCalibrate(o.capture_dir, o.settings.calibrate);
    case Stage::kReconstruct:
      return RunReconstruct(o.capture_dir, o.settings.reconstruct);
    case Stage::kFit:
      return RunFit(o.capture_dir, o.settings.fit);
    case Stage::kSimulate:
      return RunSimulate(o.capture_dir, o.settings.simulate, o.hairrig_exe);
  }
  return Internal("unknown stage");
}

std::string HostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

nlohmann::json StageResult::ToJson() const {
  return nlohmann::json{
      {"stage", StageName(stage)},  {"capture", capture_dir},   {"status", "ok"},
      {"skipped", skipped},         {"input_hash", input_hash}, {"seconds", seconds},
      {"result_file", result_file}, {"summary", summary}};
}

std::string StageResult::BriefReport() const {
  char seconds_text[32];
  std::snprintf(seconds_text, sizeof seconds_text, "%.1f", seconds);
  return std::string(StageName(stage)) + " of " + capture_dir + ": " +
         (skipped ? "skipped (inputs unchanged since its last success)"
                  : std::string("ok in ") + seconds_text + " s") +
         " (result: " + result_file + ")";
}

std::string CaptureName(const std::string& capture_dir) {
  fs::path path = fs::path(capture_dir).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  if (path.filename() == "." || path.filename().empty())
    path = fs::absolute(path).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  return path.filename().string();
}

Result<InputFiles> StageInputFiles(Stage stage, const std::string& capture_dir,
                                   const StageSettings& settings) {
  std::error_code ec;
  if (!fs::is_directory(capture_dir, ec)) return NotFound(capture_dir + ": no such capture folder");
  InputFiles files;
  switch (stage) {
    case Stage::kCalibrate:
      HR_RETURN_IF_ERROR(AddCaptureFiles(capture_dir, &files));
      for (size_t k = 0; k < settings.calibrate.intrinsics.size(); ++k) {
        const std::string key = "intrinsics[" + std::to_string(k) + "]";
        HR_RETURN_IF_ERROR(AddOptionFile(key, settings.calibrate.intrinsics[k], &files));
      }
      break;
    case Stage::kReconstruct:
      HR_RETURN_IF_ERROR(AddCaptureFiles(capture_dir, &files));
      HR_RETURN_IF_ERROR(Require(capture_dir, "calibration/calibration.json",
                                 "run the calibrate stage first", &files));
      if (!settings.reconstruct.head.empty() && settings.reconstruct.head != kFittedHead) {
        HR_RETURN_IF_ERROR(AddOptionFile("head", settings.reconstruct.head, &files));
      }
      break;
    case Stage::kFit:
      HR_RETURN_IF_ERROR(
          Require(capture_dir, kStrandsFile, "run the reconstruct stage first", &files));
      break;
    case Stage::kSimulate: {
      HR_RETURN_IF_ERROR(Require(capture_dir, kModelFile, "run the fit stage first", &files));
      HR_RETURN_IF_ERROR(
          Require(capture_dir, kStrandsFile, "run the reconstruct stage first", &files));
      HR_ASSIGN_OR_RETURN(const SimulateSettings resolved,
                          ResolvedSimulateSettings(capture_dir, settings.simulate));
      if (!resolved.head.empty()) HR_RETURN_IF_ERROR(AddOptionFile("head", resolved.head, &files));
      HR_RETURN_IF_ERROR(AddOptionFile("scene", resolved.scene, &files));
      break;
    }
  }
  return files;
}

Status StageOptions::Check() const {
  if (capture_dir.empty()) return InvalidArgument("capture_dir (--capture) is required");
  const int threads = settings.Threads(stage);
  if (threads < 1 || threads > 1024) {
    return InvalidArgument(std::string(StageName(stage)) + ".threads must lie in 1..1024, got " +
                           std::to_string(threads));
  }
  return Status::Ok();
}

Result<StageResult> RunStage(const StageOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  if (!fs::is_directory(o.capture_dir, ec))
    return NotFound(o.capture_dir + ": no such capture folder");
  const std::string context = std::string(StageName(o.stage)) + " of " + o.capture_dir;
  StageResult result;
  result.stage = o.stage;
  result.capture_dir = o.capture_dir;
  result.result_file = StageRecordPath(o.capture_dir, o.stage);

  StageRecord record;
  record.stage = StageName(o.stage);
  record.hairrig_version = HairrigVersion();
  if (const Result<std::string> build = HairrigBuildId(); build.ok()) record.hairrig_build = *build;
  record.options = o.settings.StageJson(o.stage);
  record.run_id = o.run_id;
  record.host = HostName();
  record.pid = ::getpid();
  record.start_utc = UtcNow();
  // Records a failure and returns it; a record that cannot be written is named too.
  auto fail = [&](const Status& status) -> Status {
    record.status = "failed";
    record.error = status.message();
    record.end_utc = UtcNow();
    record.seconds = SecondsSince(start);
    const Status written = WriteStageRecord(o.capture_dir, o.stage, record);
    const Status failed = status.WithContext(context);
    if (written.ok()) return failed;
    return Status(failed.code(), failed.message() + " (and the result was not recorded: " +
                                     written.message() + ")");
  };

  const std::string fault = InjectedFault(o.stage, o.capture_dir);
  if (!fault.empty()) {
    record.injected_fault = true;
    return fail(FailedPrecondition(std::string("injected fault (") + kStageFaultVariable + " has " +
                                   fault + "): this stage fails on purpose, for tests"));
  }
  Result<HashedInputs> inputs = HashInputs(o);
  if (!inputs.ok()) return fail(inputs.status());
  record.inputs = inputs->files;
  record.input_hash = result.input_hash = inputs->input_hash;

  Result<StageRecord> previous = ReadStageRecord(o.capture_dir, o.stage);
  if (!o.force && previous.ok() && previous->ok() && previous->input_hash == record.input_hash) {
    StageRecord skipped = *std::move(previous);
    skipped.skipped = true;
    skipped.run_id = o.run_id;
    skipped.checked_utc = UtcNow();
    HR_RETURN_IF_ERROR(WriteStageRecord(o.capture_dir, o.stage, skipped).WithContext(context));
    result.skipped = true;
    result.summary = skipped.summary;
    result.seconds = SecondsSince(start);
    return result;
  }

  record.status = "running";
  HR_RETURN_IF_ERROR(WriteStageRecord(o.capture_dir, o.stage, record).WithContext(context));
  Result<nlohmann::json> summary = RunStageWork(o);
  if (!summary.ok()) return fail(summary.status());
  record.status = "ok";
  record.summary = *summary;
  record.end_utc = UtcNow();
  record.seconds = SecondsSince(start);
  HR_RETURN_IF_ERROR(WriteStageRecord(o.capture_dir, o.stage, record).WithContext(context));
  result.summary = record.summary;
  result.seconds = record.seconds;
  return result;
}

}  // namespace hairrig
