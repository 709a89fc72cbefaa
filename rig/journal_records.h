// Typed records of a capture folder's JSON files (rig/capture_dataset.h):
// capture.json and the journal.jsonl records that later sessions and tools
// read back (frame_stored, view_planned, position_reached). Each FromJson
// reads through core/json_file.h's JsonObject: a missing, mistyped or
// impossible field is CorruptData naming the file, the line and the field,
// never an exception.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/status.h"

namespace hairrig {

// The largest view or stop index a record may name.
inline constexpr int kMaxViewIndex = 99999;

// The one name of a frame file, relative to the capture folder:
// "frames/003_CAM-1.png" for view 3 of the camera with serial "CAM-1". The
// serial and extension pass through FileNamePart (rig/safe_names.h), so the
// name never leaves frames/.
std::string FrameFileName(int view, const std::string& serial, const std::string& extension);
// Whether `file` is FrameFileName(view, serial, its own extension).
bool IsFrameFileName(const std::string& file, int view, const std::string& serial);

// "<journal_path>: line <index + 1>", naming a journal record in messages.
std::string JournalLine(const std::string& journal_path, size_t index);
// The record's "event", or "" when it has none (or it is not text).
std::string JournalEvent(const nlohmann::json& record);

// capture.json, written once when the capture is created.
struct CaptureMetadata {
  std::string config_source;  // the config file the capture was started from
  std::string config_dir;     // the folder the config's relative paths resolve against
  std::string subject;
  std::string created_utc;

  nlohmann::json ToJson() const;  // with "format": "hairrig-capture" and "version": 1
  // CorruptData for another format or version, or a mistyped field.
  static Result<CaptureMetadata> FromJson(const nlohmann::json& j, const std::string& where);
};

// frame_stored: a frame written to frames/, vouched for by its size and SHA-256.
struct FrameRecord {
  int view = 0;
  int stop = 0;
  std::string camera;  // the camera's name in the rig config
  std::string serial;  // never empty
  std::string file;    // FrameFileName(view, serial, extension)
  uint64_t bytes = 0;
  std::string sha256;  // 64 lower-case hex characters
  int width_px = 0;
  int height_px = 0;
  std::string pixel_format;
  double exposure_s = 0;
  double gain_db = 0;
  int64_t trigger_time_ns = 0;
  int64_t received_time_ns = 0;
  double angle_commanded_deg = 0;
  double angle_measured_deg = 0;

  nlohmann::json ToJson() const;  // with "event": "frame_stored"
  // CorruptData naming `where` and the field for a field missing or of the
  // wrong type, an empty serial, a view or stop that is negative, fractional
  // or above kMaxViewIndex, bytes that are not a non-negative integer, a
  // sha256 that is not 64 hex characters, a file other than FrameFileName.
  static Result<FrameRecord> FromJson(const nlohmann::json& j, const std::string& where);
};

// view_planned: one view of the plan the capture was started with.
struct PlannedViewRecord {
  int view = 0;
  int stop = 0;
  double angle_deg = 0;
  std::string camera;
  std::string serial;
  std::map<std::string, double> lights;  // light name -> level 0..1

  nlohmann::json ToJson() const;  // with "event": "view_planned"
  static Result<PlannedViewRecord> FromJson(const nlohmann::json& j, const std::string& where);
  // "view 3 (stop 1 at 9.47 deg, camera lower SIM-CAM-LOWER, lights bottom=1 top=0)".
  std::string Describe() const;
  bool operator==(const PlannedViewRecord&) const = default;
};

// position_reached: the turntable arrived at a stop.
struct PositionRecord {
  double commanded_deg = 0;
  double measured_deg = 0;
  std::string time_utc;

  static Result<PositionRecord> FromJson(const nlohmann::json& j, const std::string& where);
};

}  // namespace hairrig
