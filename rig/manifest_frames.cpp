#include "rig/manifest_frames.h"

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/file_util.h"
#include "core/json_file.h"
#include "rig/capture_dataset.h"
#include "rig/journal_records.h"

namespace hairrig {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifestAltered =
    "the manifest was altered: rewrite it with `hairrig capture --resume`";

}  // namespace

Status CheckFramesFolder(const std::string& capture_dir) {
  const std::string frames = (fs::path(capture_dir) / "frames").string();
  const Result<std::string> inside = ResolveInside(frames, capture_dir);
  if (inside.ok() || inside.status().code() != StatusCode::kCorruptData) return inside.status();
  return FailedPrecondition(inside.status().message() +
                            ": frames are read only from inside the capture folder; replace " +
                            frames + " by the folder it leads to");
}

Result<std::vector<ManifestFrame>> ReadManifestFrames(const std::string& capture_dir) {
  const std::string manifest_path = (fs::path(capture_dir) / "manifest.json").string();
  HR_ASSIGN_OR_RETURN(const nlohmann::json manifest,
                      ReadJsonFile(manifest_path, "is this a capture folder?"));
  const JsonObject root(manifest, manifest_path);
  std::vector<ManifestFrame> frames;
  std::set<int> views_seen;
  std::map<int, FrameContent> contents;
  for (const JsonObject& f : root.Objects("frames")) {
    ManifestFrame frame;
    frame.record = f.Describe("");
    frame.serial_field = f.Describe("serial");
    frame.view = static_cast<int>(f.Integer("view", {.min = 0, .max = kMaxViewIndex}));
    if (f.ok() && !views_seen.insert(frame.view).second) {
      // Refused at the first repeat: a list repeated thousands of times costs nothing.
      f.Fail("view",
             "view " + std::to_string(frame.view) + " is listed twice; " + kManifestAltered);
      break;
    }
    frame.stop = static_cast<int>(f.Integer("stop", {.min = 0, .max = kMaxViewIndex}));
    frame.angle_measured_deg = f.Number("angle_measured_deg");
    frame.file = f.String("file");
    frame.serial = f.String("serial");
    frame.bytes = static_cast<uint64_t>(f.Integer("bytes", {.min = 0}));
    frame.sha256 = f.String("sha256");
    if (!f.ok()) break;
    if (!IsFrameFileName(frame.file, frame.view, frame.serial)) {
      f.Fail("file", frame.file + " is not the file of view " + std::to_string(frame.view) +
                         " from camera " + frame.serial);
      break;
    }
    frame.path = (fs::path(capture_dir) / frame.file).lexically_normal().string();
    contents[frame.view] = {frame.sha256, frame.record, f.Describe("sha256")};
    frames.push_back(std::move(frame));
  }
  HR_RETURN_IF_ERROR(root.status());
  HR_RETURN_IF_ERROR(CheckDistinctContent(contents, kManifestAltered));
  return frames;
}

Status VerifyManifestFrames(const std::string& capture_dir, std::vector<ManifestFrame>* frames) {
  HR_RETURN_IF_ERROR(CheckFramesFolder(capture_dir));
  for (ManifestFrame& frame : *frames) {
    const Result<std::string> verified =
        VerifyFrameFile(capture_dir, frame.file, frame.bytes, frame.sha256);
    if (verified.ok()) {
      frame.path = *verified;
      frame.unusable.clear();
    } else {
      frame.unusable = verified.status().message() + " (`hairrig capture --resume` re-shoots it)";
    }
  }
  return Status::Ok();
}

}  // namespace hairrig
