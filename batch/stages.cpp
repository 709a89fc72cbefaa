#include "batch/stages.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/json_file.h"
#include "rig/reconstruction_input.h"
#include "simulation/hair_simulation.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr JsonIntRange kThreads{.min = 1, .max = 1024};

std::string ResolveAgainst(const std::string& base_dir, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute() || base_dir.empty()) return path;
  return (fs::path(base_dir) / path).lexically_normal().string();
}

// Fails `key` unless its value is one of `choices`.
void CheckChoice(const JsonObject& o, const char* key, const std::string& value,
                 std::initializer_list<const char*> choices) {
  std::string listed;
  for (const char* choice : choices) {
    if (value == choice) return;
    listed += listed.empty() ? choice : std::string(", ") + choice;
  }
  o.Fail(key, "'" + value + "' is not one of " + listed);
}

void CheckKnownKeys(const JsonObject& o, std::initializer_list<const char*> known) {
  for (const std::string& key : o.Keys()) {
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; })) {
      std::string listed;
      for (const char* k : known) listed += listed.empty() ? k : std::string(", ") + k;
      o.Fail(key, "unknown field (known: " + listed + ")");
    }
  }
}

std::vector<std::string> FileListOr(const JsonObject& o, const char* key,
                                    std::vector<std::string> fallback) {
  if (!o.Has(key)) return fallback;
  const nlohmann::json& list = o.Raw(key);
  std::vector<std::string> files;
  if (!list.is_array()) {
    o.Fail(key, "expected an array of file names");
    return files;
  }
  for (const nlohmann::json& item : list) {
    if (!item.is_string()) {
      o.Fail(key, "expected an array of file names");
      return {};
    }
    files.push_back(item.get<std::string>());
  }
  return files;
}

// True when `key` is present as an object; fails it when present as anything else.
bool HasSection(const JsonObject& root, const char* key) {
  if (!root.Has(key)) return false;
  if (root.Raw(key).is_object()) return true;
  root.Fail(key, "expected an object of the stage's options");
  return false;
}

void ReadCalibrate(const JsonObject& o, const std::string& base_dir, CalibrateSettings* s) {
  CheckKnownKeys(o, {"mode", "intrinsics", "hard_prior", "threads"});
  s->mode = o.StringOr("mode", s->mode);
  CheckChoice(o, "mode", s->mode, {"turntable", "free"});
  s->intrinsics = FileListOr(o, "intrinsics", s->intrinsics);
  for (std::string& file : s->intrinsics) file = ResolveAgainst(base_dir, file);
  s->hard_prior = o.BoolOr("hard_prior", s->hard_prior);
  s->threads = static_cast<int>(o.IntegerOr("threads", s->threads, kThreads));
}

void ReadReconstruct(const JsonObject& o, const std::string& base_dir, ReconstructSettings* s) {
  CheckKnownKeys(
      o, {"method", "strands", "head", "stride_px", "iterations", "hull_voxel_mm", "threads"});
  s->method = o.StringOr("method", s->method);
  CheckChoice(o, "method", s->method, {"bao-qi", "luo", "naive"});
  s->strands = static_cast<int>(o.IntegerOr("strands", s->strands, {.min = 1, .max = 2000000}));
  const std::string head = o.StringOr("head", s->head);
  s->head = head == kFittedHead ? head : ResolveAgainst(base_dir, head);
  s->stride_px = static_cast<int>(o.IntegerOr("stride_px", s->stride_px, {.min = 1, .max = 8}));
  s->iterations = static_cast<int>(o.IntegerOr("iterations", s->iterations, {.min = 1, .max = 50}));
  s->hull_voxel_mm = o.NumberOr("hull_voxel_mm", s->hull_voxel_mm, {.min = 0.25, .max = 50});
  s->threads = static_cast<int>(o.IntegerOr("threads", s->threads, kThreads));
}

void ReadFit(const JsonObject& o, FitSettings* s) {
  CheckKnownKeys(o, {"guides", "target_error_mm", "threads"});
  s->guides = static_cast<int>(o.IntegerOr("guides", s->guides, {.min = 1, .max = 10000000}));
  s->target_error_mm = o.NumberOr("target_error_mm", s->target_error_mm, {.min = 0});
  s->threads = static_cast<int>(o.IntegerOr("threads", s->threads, kThreads));
}

void ReadSimulate(const JsonObject& o, const std::string& base_dir, SimulateSettings* s) {
  CheckKnownKeys(o, {"scenario", "seconds", "fps", "preview_every", "head", "scene"});
  s->scenario = o.StringOr("scenario", s->scenario);
  if (o.ok() && !ParseScenario(s->scenario).ok())
    o.Fail("scenario", ParseScenario(s->scenario).status().message());
  s->seconds = o.NumberOr("seconds", s->seconds, {.min = 1e-3, .max = 3600});
  s->fps = o.NumberOr("fps", s->fps, {.min = 1e-3, .max = 10000});
  s->preview_every =
      static_cast<int>(o.IntegerOr("preview_every", s->preview_every, {.min = 0, .max = 1000000}));
  s->head = ResolveAgainst(base_dir, o.StringOr("head", s->head));
  s->scene = ResolveAgainst(base_dir, o.StringOr("scene", s->scene));
}

}  // namespace

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kCalibrate:
      return "calibrate";
    case Stage::kReconstruct:
      return "reconstruct";
    case Stage::kFit:
      return "fit";
    case Stage::kSimulate:
      return "simulate";
  }
  return "?";
}

const char* StageFolder(Stage stage) {
  switch (stage) {
    case Stage::kCalibrate:
      return "calibration";
    case Stage::kReconstruct:
      return "reconstruction";
    case Stage::kFit:
      return "fit";
    case Stage::kSimulate:
      return "simulation";
  }
  return "?";
}

Result<Stage> ParseStage(const std::string& name) {
  for (Stage stage : kAllStages) {
    if (name == StageName(stage)) return stage;
  }
  return InvalidArgument("unknown stage '" + name +
                         "' (stages: calibrate, reconstruct, fit, simulate)");
}

Result<std::vector<Stage>> ParseStageList(const std::vector<std::string>& names) {
  std::set<Stage> chosen;
  for (const std::string& name : names) {
    std::istringstream parts(name);
    for (std::string part; std::getline(parts, part, ',');) {
      if (part.empty()) continue;
      HR_ASSIGN_OR_RETURN(const Stage stage, ParseStage(part));
      chosen.insert(stage);
    }
  }
  if (chosen.empty()) return std::vector<Stage>(kAllStages.begin(), kAllStages.end());
  return std::vector<Stage>(chosen.begin(), chosen.end());  // the enum's order is the pipeline's
}

nlohmann::json StageSettings::StageJson(Stage stage) const {
  switch (stage) {
    case Stage::kCalibrate:
      return {{"mode", calibrate.mode},
              {"intrinsics", calibrate.intrinsics},
              {"hard_prior", calibrate.hard_prior},
              {"threads", calibrate.threads}};
    case Stage::kReconstruct:
      return {{"method", reconstruct.method},
              {"strands", reconstruct.strands},
              {"head", reconstruct.head},
              {"stride_px", reconstruct.stride_px},
              {"iterations", reconstruct.iterations},
              {"hull_voxel_mm", reconstruct.hull_voxel_mm},
              {"threads", reconstruct.threads}};
    case Stage::kFit:
      return {{"guides", fit.guides},
              {"target_error_mm", fit.target_error_mm},
              {"threads", fit.threads}};
    case Stage::kSimulate:
      return {{"scenario", simulate.scenario}, {"seconds", simulate.seconds},
              {"fps", simulate.fps},           {"preview_every", simulate.preview_every},
              {"head", simulate.head},         {"scene", simulate.scene}};
  }
  return nlohmann::json::object();
}

nlohmann::json StageSettings::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (Stage stage : kAllStages) j[StageName(stage)] = StageJson(stage);
  return j;
}

int StageSettings::Threads(Stage stage) const {
  switch (stage) {
    case Stage::kCalibrate:
      return calibrate.threads;
    case Stage::kReconstruct:
      return reconstruct.threads;
    case Stage::kFit:
      return fit.threads;
    case Stage::kSimulate:
      return 1;
  }
  return 1;
}

Result<StageSettings> StageSettingsFromJson(const nlohmann::json& j, const std::string& where,
                                            const std::string& base_dir) {
  StageSettings s;
  const JsonObject root(j, where);
  if (!j.is_object()) {
    root.Fail("", "expected an object with sections calibrate, reconstruct, fit, simulate");
    return root.status();
  }
  CheckKnownKeys(root, {"calibrate", "reconstruct", "fit", "simulate"});
  if (HasSection(root, "calibrate"))
    ReadCalibrate(root.Object("calibrate"), base_dir, &s.calibrate);
  if (HasSection(root, "reconstruct"))
    ReadReconstruct(root.Object("reconstruct"), base_dir, &s.reconstruct);
  if (HasSection(root, "fit")) ReadFit(root.Object("fit"), &s.fit);
  if (HasSection(root, "simulate")) ReadSimulate(root.Object("simulate"), base_dir, &s.simulate);
  HR_RETURN_IF_ERROR(root.status());
  return s;
}

Result<StageSettings> LoadStageSettings(const std::string& path) {
  if (path.empty()) return StageSettings{};
  HR_ASSIGN_OR_RETURN(const nlohmann::json j,
                      ReadJsonFile(path, "give a JSON file of stage options (batch/stages.h)"));
  return StageSettingsFromJson(j, path, fs::absolute(path).parent_path().string());
}

}  // namespace hairrig
