// The captures in the console's folder, addressed by id: the capture folder's
// name, never a path a client sends. Every file served resolves, symlinks
// included, inside its capture (core/file_util.h ResolveInside), and only files
// of a fixed set of kinds are served.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// InvalidArgument unless `id` is 1-128 characters of [A-Za-z0-9._-] starting
// with a letter or digit.
Status CheckCaptureId(const std::string& id);

struct ArchiveEntry {
  std::string id;
  std::string subject;
  // The manifest's: "complete", "incomplete", "stopped", "in_progress"
  // (being shot, or interrupted: resumable), or "unreadable" (see message).
  std::string status;
  std::string message;
  int views_completed = 0;
  int views_planned = 0;
  std::string started_utc;             // capture.json's creation time
  std::optional<std::string> verdict;  // calibration/report/verdict.json
  std::optional<double> calibration_rms_px;
  bool reconstructed = false;  // reconstruction/strands/strands.ply exists

  nlohmann::json ToJson() const;
};

class CaptureArchive {
 public:
  explicit CaptureArchive(std::string root) : root_(std::move(root)) {}
  const std::string& root() const { return root_; }

  // Every folder of the root with a manifest.json, newest first. A capture
  // whose files cannot be read is listed as "unreadable" with why.
  std::vector<ArchiveEntry> List() const;
  // The capture's folder: InvalidArgument for a bad id, NotFound when no such
  // capture exists (no manifest.json), CorruptData when it resolves outside the root.
  Result<std::string> CaptureDir(const std::string& id) const;
  Result<ArchiveEntry> Entry(const std::string& id) const;
  // Entry plus "views" [{view, camera, thumb}], "calibration" {verdict,
  // rms_px, reasons, views [{name, rms_px, solved}], residuals [urls]} or
  // null, "reconstruction" {verdict, reasons} (reconstruction/verdict.json) or
  // null, "reconstruction_figures" {points, direction_agreement (0..1),
  // strands, strand_mean_length_mm; each null when not measured}, and "files"
  // {contact_sheet, journal, view_rms, reconstruction [urls of pictures],
  // simulation [urls], model (the 3D view's reconstruction/strands/
  // hair.display.glb, or null), downloads [urls of points.ply, the strand
  // files and .glb files]} (urls under /api/captures/<id>/).
  Result<nlohmann::json> Details(const std::string& id) const;
  // A file of the capture by its path relative to the capture folder, if it
  // is of a kind served (contact_sheet.png, journal.jsonl, manifest.json, the
  // calibration report's text, verdict, RMS chart and residual images, the
  // reconstruction's verdict and the reconstruction's and the simulation's
  // pictures; the reconstruction's points.ply, strands.{ply,hair,data} and
  // strands/*.glb): InvalidArgument for any other path, NotFound when absent.
  Result<std::string> FilePath(const std::string& id, const std::string& relative) const;
  // View `view`'s stored frame as a JPEG at most `max_width_px` wide.
  Result<std::vector<uint8_t>> Thumbnail(const std::string& id, int view, int max_width_px) const;

 private:
  ArchiveEntry ReadEntry(const std::string& id, const std::string& dir) const;
  std::string root_;
};

// "image/jpeg", "image/png", "application/json", "text/plain; charset=utf-8"
// (.txt, .jsonl) by the file's extension; "application/octet-stream" otherwise.
std::string ContentTypeOf(const std::string& path);

}  // namespace hairrig
