#include "console/capture_archive.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "console/preview_image.h"
#include "core/file_util.h"
#include "core/json_file.h"
#include "core/log.h"
#include "rig/safe_names.h"

namespace hairrig {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifest = "manifest.json";

// The kinds of file a client may ask for, relative to the capture folder.
bool IsServedFile(const std::string& relative) {
  static const std::regex served(
      "contact_sheet\\.png|journal\\.jsonl|manifest\\.json"
      "|calibration/report/(view_rms\\.png|report\\.txt|verdict\\.json"
      "|residuals/[A-Za-z0-9_-][A-Za-z0-9._-]*\\.jpg)"
      "|reconstruction/verdict\\.json|reconstruction/points\\.ply"
      "|reconstruction/strands/(strands\\.(ply|hair|data)|[A-Za-z0-9_-]+(\\.display)?\\.glb)"
      "|reconstruction/([A-Za-z0-9_-]+/)?[A-Za-z0-9_-][A-Za-z0-9._-]*\\.(jpg|png)"
      "|simulation/[A-Za-z0-9_-][A-Za-z0-9._-]*/[A-Za-z0-9_-][A-Za-z0-9._-]*\\.png");
  return relative.size() <= 256 && std::regex_match(relative, served);
}

std::string Url(const std::string& id, const std::string& relative) {
  return "/api/captures/" + id + "/files/" + relative;
}

// Files under `dir` (relative to `capture_dir`) that are served, sorted.
std::vector<std::string> ServedFilesUnder(const fs::path& capture_dir, const std::string& dir,
                                          bool recursive) {
  std::vector<std::string> out;
  std::error_code ec;
  const fs::path root = capture_dir / dir;
  if (!fs::is_directory(root, ec)) return out;
  auto consider = [&](const fs::directory_entry& e) {
    if (!e.is_regular_file(ec)) return;
    const std::string relative = fs::relative(e.path(), capture_dir, ec).generic_string();
    if (!ec && IsServedFile(relative)) out.push_back(relative);
  };
  if (recursive) {
    for (const auto& e : fs::recursive_directory_iterator(root, ec)) consider(e);
  } else {
    for (const auto& e : fs::directory_iterator(root, ec)) consider(e);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A verdict's "reasons": a list of strings (anything else is recorded as an error).
nlohmann::json Reasons(const JsonObject& verdict) {
  const nlohmann::json& reasons = verdict.Raw("reasons");
  if (reasons.is_array() && std::all_of(reasons.begin(), reasons.end(),
                                        [](const nlohmann::json& r) { return r.is_string(); }))
    return reasons;
  verdict.Fail("reasons", "is not a list of strings");
  return nlohmann::json::array();
}

// The calibration's summary from calibration.json and the report's verdict.json.
nlohmann::json CalibrationDetails(const std::string& id, const fs::path& dir) {
  Result<nlohmann::json> verdict = ReadJsonFile((dir / "calibration/report/verdict.json").string());
  Result<nlohmann::json> calibration =
      ReadJsonFile((dir / "calibration/calibration.json").string());
  if (!verdict.ok() || !calibration.ok()) return nullptr;
  const JsonObject v(*verdict, "verdict.json");
  const JsonObject c(*calibration, "calibration.json");
  nlohmann::json out = {{"verdict", v.String("verdict")},
                        {"reasons", Reasons(v)},
                        {"rms_px", c.Number("rms_px")},
                        {"views", nlohmann::json::array()},
                        {"residuals", nlohmann::json::array()}};
  for (const JsonObject& view : c.Objects("views")) {
    const bool solved = view.Bool("solved");
    out["views"].push_back({{"name", view.String("frame")},
                            {"solved", solved},
                            {"rms_px", solved ? view.Number("rms_px") : 0.0}});
  }
  if (!v.ok() || !c.ok()) return nullptr;
  for (const std::string& f : ServedFilesUnder(dir, "calibration/report/residuals", false))
    out["residuals"].push_back(Url(id, f));
  return out;
}

// The reconstruction's verdict.json ({verdict, reasons}), or null.
nlohmann::json ReconstructionVerdictDetails(const fs::path& dir) {
  Result<nlohmann::json> verdict = ReadJsonFile((dir / "reconstruction/verdict.json").string());
  if (!verdict.ok()) return nullptr;
  const JsonObject v(*verdict, "reconstruction/verdict.json");
  nlohmann::json out = {{"verdict", v.String("verdict")}, {"reasons", Reasons(v)}};
  return v.ok() ? out : nullptr;
}

// The reconstruction's headline figures from its summaries (each null when
// its summary lacks it): oriented points, the share of depth-agreeing view
// pairs that also agree on the direction (the verdict's check), strands and
// their mean length (mm).
nlohmann::json ReconstructionFigures(const fs::path& dir) {
  nlohmann::json out = {{"points", nullptr},
                        {"direction_agreement", nullptr},
                        {"strands", nullptr},
                        {"strand_mean_length_mm", nullptr}};
  if (Result<nlohmann::json> points = ReadJsonFile((dir / "reconstruction/summary.json").string());
      points.ok()) {
    const JsonObject fusion = JsonObject(*points, "reconstruction/summary.json").Object("fusion");
    const double depth_pairs = fusion.NumberOr("depth_pairs", 0, {.min = 0});
    if (fusion.Has("points")) out["points"] = fusion.Integer("points", {.min = 0});
    if (depth_pairs > 0)
      out["direction_agreement"] = fusion.NumberOr("direction_pairs", 0, {.min = 0}) / depth_pairs;
    if (!fusion.ok()) {
      LogWarning("console: " + fusion.status().ToString());
      out["points"] = out["direction_agreement"] = nullptr;
    }
  }
  if (Result<nlohmann::json> strands =
          ReadJsonFile((dir / "reconstruction/strands/summary.json").string());
      strands.ok()) {
    const JsonObject s =
        JsonObject(*strands, "reconstruction/strands/summary.json").Object("strands");
    const int64_t count = s.Integer("count", {.min = 0});
    const double length = s.Number("mean_length_mm", {.min = 0});
    if (s.ok()) {
      out["strands"] = count;
      out["strand_mean_length_mm"] = length;
    } else {
      LogWarning("console: " + s.status().ToString());
    }
  }
  return out;
}

}  // namespace

Status CheckCaptureId(const std::string& id) {
  static const std::regex valid("[A-Za-z0-9][A-Za-z0-9._-]{0,127}");
  if (!std::regex_match(id, valid))
    return InvalidArgument("capture id '" + id.substr(0, 40) +
                           "': 1-128 letters, digits, '.', '_' or '-', starting with a letter "
                           "or digit (the capture folder's name)");
  return Status::Ok();
}

nlohmann::json ArchiveEntry::ToJson() const {
  nlohmann::json j = {{"id", id},
                      {"subject", subject},
                      {"status", status},
                      {"views_completed", views_completed},
                      {"views_planned", views_planned},
                      {"started", started_utc},
                      {"calibration", nullptr},
                      {"reconstructed", reconstructed}};
  if (!message.empty()) j["message"] = message;
  if (verdict)
    j["calibration"] = {{"verdict", *verdict}, {"rms_px", calibration_rms_px.value_or(0)}};
  return j;
}

ArchiveEntry CaptureArchive::ReadEntry(const std::string& id, const std::string& dir) const {
  ArchiveEntry entry;
  entry.id = id;
  Result<nlohmann::json> manifest = ReadJsonFile(dir + "/" + kManifest);
  if (!manifest.ok()) {
    entry.status = "unreadable";
    entry.message = manifest.status().ToString();
    return entry;
  }
  const JsonObject m(*manifest, id + "/manifest.json");
  entry.subject = m.StringOr("subject", "");
  entry.status = m.String("status");
  entry.views_completed =
      static_cast<int>(m.Integer("views_completed", {.min = 0, .max = 1 << 20}));
  entry.views_planned = static_cast<int>(m.Integer("views_planned", {.min = 0, .max = 1 << 20}));
  if (!m.ok()) {
    entry.status = "unreadable";
    entry.message = m.status().ToString();
    return entry;
  }
  if (Result<nlohmann::json> meta = ReadJsonFile(dir + "/capture.json"); meta.ok()) {
    const JsonObject c(*meta, id + "/capture.json");
    entry.started_utc = c.StringOr("created_utc", "");
  }
  const nlohmann::json calibration = CalibrationDetails(id, dir);
  if (!calibration.is_null()) {
    entry.verdict = calibration["verdict"].get<std::string>();
    entry.calibration_rms_px = calibration["rms_px"].get<double>();
  }
  std::error_code ec;
  entry.reconstructed =
      fs::is_regular_file(fs::path(dir) / "reconstruction/strands/strands.ply", ec);
  return entry;
}

std::vector<ArchiveEntry> CaptureArchive::List() const {
  std::vector<ArchiveEntry> entries;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(root_, ec)) {
    const std::string id = e.path().filename().string();
    if (!CheckCaptureId(id).ok() || !e.is_directory(ec)) continue;
    if (!fs::exists(e.path() / kManifest, ec)) continue;
    Result<std::string> dir = CaptureDir(id);
    if (!dir.ok()) continue;
    entries.push_back(ReadEntry(id, *dir));
  }
  std::sort(entries.begin(), entries.end(), [](const ArchiveEntry& a, const ArchiveEntry& b) {
    return a.started_utc != b.started_utc ? a.started_utc > b.started_utc : a.id < b.id;
  });
  return entries;
}

Result<std::string> CaptureArchive::CaptureDir(const std::string& id) const {
  HR_RETURN_IF_ERROR(CheckCaptureId(id));
  const std::string dir = (fs::path(root_) / id).string();
  std::error_code ec;
  if (!fs::is_directory(dir, ec) || !fs::exists(fs::path(dir) / kManifest, ec))
    return NotFound("no capture '" + id + "' in " + root_);
  return ResolveInside(dir, root_);
}

Result<ArchiveEntry> CaptureArchive::Entry(const std::string& id) const {
  HR_ASSIGN_OR_RETURN(const std::string dir, CaptureDir(id));
  return ReadEntry(id, dir);
}

Result<nlohmann::json> CaptureArchive::Details(const std::string& id) const {
  HR_ASSIGN_OR_RETURN(const std::string dir, CaptureDir(id));
  const ArchiveEntry entry = ReadEntry(id, dir);
  nlohmann::json out = entry.ToJson();
  out["views"] = nlohmann::json::array();
  if (Result<nlohmann::json> manifest = ReadJsonFile(dir + "/" + kManifest); manifest.ok()) {
    const JsonObject m(*manifest, id + "/manifest.json");
    for (const JsonObject& frame : m.Objects("frames")) {
      const int64_t view = frame.Integer("view", {.min = 0, .max = 1 << 20});
      if (!m.ok()) break;
      out["views"].push_back(
          {{"view", view},
           {"camera", frame.StringOr("camera", "")},
           {"thumb", "/api/captures/" + id + "/views/" + std::to_string(view) + "/thumb.jpg"}});
    }
  }
  const fs::path root(dir);
  out["calibration"] = CalibrationDetails(id, root);
  out["reconstruction"] = ReconstructionVerdictDetails(root);
  out["reconstruction_figures"] = ReconstructionFigures(root);
  std::error_code ec;
  auto url_if = [&](const std::string& relative) -> nlohmann::json {
    if (fs::is_regular_file(root / relative, ec)) return Url(id, relative);
    return nullptr;
  };
  nlohmann::json reconstruction = nlohmann::json::array(), simulation = nlohmann::json::array();
  nlohmann::json downloads = nlohmann::json::array();
  for (const std::string& f : ServedFilesUnder(root, "reconstruction", true)) {
    if (f.ends_with(".jpg") || f.ends_with(".png")) {
      reconstruction.push_back(Url(id, f));
    } else if (!f.ends_with(".json")) {
      downloads.push_back(Url(id, f));  // points, strands, glTF
    }
  }
  for (const std::string& f : ServedFilesUnder(root, "simulation", true)) {
    if (simulation.size() < 8) simulation.push_back(Url(id, f));
  }
  out["files"] = {{"contact_sheet", url_if("contact_sheet.png")},
                  {"journal", Url(id, "journal.jsonl")},
                  {"view_rms", url_if("calibration/report/view_rms.png")},
                  {"reconstruction", reconstruction},
                  {"simulation", simulation},
                  {"model", url_if("reconstruction/strands/hair.display.glb")},
                  {"downloads", downloads}};
  return out;
}

Result<std::string> CaptureArchive::FilePath(const std::string& id,
                                             const std::string& relative) const {
  HR_ASSIGN_OR_RETURN(const std::string dir, CaptureDir(id));
  if (!IsServedFile(relative))
    return InvalidArgument("'" + relative.substr(0, 80) +
                           "' is not a file the console serves (the contact sheet, journal, "
                           "manifest, calibration report, reconstruction verdict, the pipeline's "
                           "pictures and the reconstruction's points, strands and glTF files)");
  const std::string path = (fs::path(dir) / relative).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(id + "/" + relative + " does not exist");
  return ResolveInside(path, dir);
}

Result<std::vector<uint8_t>> CaptureArchive::Thumbnail(const std::string& id, int view,
                                                       int max_width_px) const {
  HR_ASSIGN_OR_RETURN(const std::string dir, CaptureDir(id));
  HR_ASSIGN_OR_RETURN(const nlohmann::json manifest, ReadJsonFile(dir + "/" + kManifest));
  const JsonObject m(manifest, id + "/manifest.json");
  for (const JsonObject& frame : m.Objects("frames")) {
    if (frame.Integer("view") != view) continue;
    const std::string file = frame.String("file");
    HR_RETURN_IF_ERROR(m.status());
    HR_ASSIGN_OR_RETURN(const std::string path, ResolveInside(dir + "/" + file, dir));
    HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path));
    const int reduce = max_width_px * 4 <= 1600 ? cv::IMREAD_REDUCED_COLOR_4 : cv::IMREAD_COLOR;
    const cv::Mat image = cv::imdecode(bytes, reduce);
    if (image.empty()) return CorruptData(id + "/" + file + ": does not decode");
    return EncodePreviewJpeg(image, max_width_px);
  }
  HR_RETURN_IF_ERROR(m.status());
  return NotFound("capture '" + id + "' has no stored frame for view " + std::to_string(view));
}

std::string ContentTypeOf(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".txt" || ext == ".jsonl") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

}  // namespace hairrig
