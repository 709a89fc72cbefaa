#include "rig/journal_records.h"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/json_file.h"
#include "rig/safe_names.h"

namespace hairrig {

namespace {

constexpr int64_t kMaxPixels = 1 << 20;  // per image side

// The text as a JSON string literal, control characters escaped, cut at 80 characters.
std::string Quoted(const std::string& text) {
  std::string q =
      nlohmann::json(text).dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
  if (q.size() > 80) q = q.substr(0, 77) + "...";
  return q;
}

bool IsSha256Hex(const std::string& text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::string ExtensionOf(const std::string& file) {
  const size_t dot = file.find_last_of('.');
  return dot == std::string::npos ? "" : file.substr(dot + 1);
}

int Index(const JsonObject& o, const char* key) {
  return static_cast<int>(o.Integer(key, {.min = 0, .max = kMaxViewIndex}));
}

}  // namespace

std::string FrameFileName(int view, const std::string& serial, const std::string& extension) {
  char number[16];
  std::snprintf(number, sizeof number, "%03d_", view);
  return "frames/" + std::string(number) + FileNamePart(serial) + "." + FileNamePart(extension);
}

bool IsFrameFileName(const std::string& file, int view, const std::string& serial) {
  return file == FrameFileName(view, serial, ExtensionOf(file));
}

std::string JournalLine(const std::string& journal_path, size_t index) {
  return journal_path + ": line " + std::to_string(index + 1);
}

std::string JournalEvent(const nlohmann::json& record) {
  if (!record.is_object()) return "";
  const auto event = record.find("event");
  return event != record.end() && event->is_string() ? event->get<std::string>() : "";
}

nlohmann::json CaptureMetadata::ToJson() const {
  return {{"format", "hairrig-capture"}, {"version", 1},       {"config_source", config_source},
          {"config_dir", config_dir},    {"subject", subject}, {"created_utc", created_utc}};
}

Result<CaptureMetadata> CaptureMetadata::FromJson(const nlohmann::json& j,
                                                  const std::string& where) {
  const JsonObject o(j, where);
  if (o.StringOr("format", "") != "hairrig-capture" || !o.ok())
    return CorruptData(where +
                       " is not a hairrig capture description: was the folder made by hairrig?");
  if (o.Integer("version") != 1 && o.ok())
    o.Fail("version", "this build reads captures of version 1");
  CaptureMetadata m;
  m.config_source = o.StringOr("config_source", "");
  m.config_dir = o.StringOr("config_dir", "");
  m.subject = o.StringOr("subject", "");
  m.created_utc = o.StringOr("created_utc", "");
  HR_RETURN_IF_ERROR(o.status());
  return m;
}

nlohmann::json FrameRecord::ToJson() const {
  return {{"event", "frame_stored"},
          {"view", view},
          {"stop", stop},
          {"camera", camera},
          {"serial", serial},
          {"file", file},
          {"bytes", bytes},
          {"sha256", sha256},
          {"width_px", width_px},
          {"height_px", height_px},
          {"pixel_format", pixel_format},
          {"exposure_s", exposure_s},
          {"gain_db", gain_db},
          {"trigger_time_ns", trigger_time_ns},
          {"received_time_ns", received_time_ns},
          {"angle_commanded_deg", angle_commanded_deg},
          {"angle_measured_deg", angle_measured_deg}};
}

Result<FrameRecord> FrameRecord::FromJson(const nlohmann::json& j, const std::string& where) {
  const JsonObject o(j, where);
  FrameRecord f;
  f.view = Index(o, "view");
  f.stop = Index(o, "stop");
  f.camera = o.StringOr("camera", "");
  f.serial = o.String("serial");
  f.file = o.String("file");
  f.bytes = static_cast<uint64_t>(o.Integer("bytes", {.min = 0}));
  f.sha256 = o.String("sha256");
  f.width_px = static_cast<int>(o.IntegerOr("width_px", 0, {.min = 0, .max = kMaxPixels}));
  f.height_px = static_cast<int>(o.IntegerOr("height_px", 0, {.min = 0, .max = kMaxPixels}));
  f.pixel_format = o.StringOr("pixel_format", "");
  f.exposure_s = o.NumberOr("exposure_s", 0, {.min = 0});
  f.gain_db = o.NumberOr("gain_db", 0);
  f.trigger_time_ns = o.IntegerOr("trigger_time_ns", 0);
  f.received_time_ns = o.IntegerOr("received_time_ns", 0);
  f.angle_commanded_deg = o.Number("angle_commanded_deg");
  f.angle_measured_deg = o.Number("angle_measured_deg");
  if (o.ok() && f.serial.empty()) o.Fail("serial", "is empty");
  if (o.ok() && !IsSha256Hex(f.sha256))
    o.Fail("sha256", "expected 64 lower-case hexadecimal characters, got " + Quoted(f.sha256));
  if (o.ok() && !IsFrameFileName(f.file, f.view, f.serial)) {
    o.Fail("file", Quoted(f.file) + " is not the file of view " + std::to_string(f.view) +
                       " from camera " + Quoted(f.serial) + " (" +
                       FrameFileName(f.view, f.serial, ExtensionOf(f.file)) + ")");
  }
  HR_RETURN_IF_ERROR(o.status());
  return f;
}

nlohmann::json PlannedViewRecord::ToJson() const {
  return {{"event", "view_planned"}, {"view", view},     {"stop", stop},
          {"angle_deg", angle_deg},  {"camera", camera}, {"serial", serial},
          {"lights", lights}};
}

Result<PlannedViewRecord> PlannedViewRecord::FromJson(const nlohmann::json& j,
                                                      const std::string& where) {
  const JsonObject o(j, where);
  PlannedViewRecord v;
  v.view = Index(o, "view");
  v.stop = Index(o, "stop");
  v.angle_deg = o.Number("angle_deg");
  v.camera = o.StringOr("camera", "");
  v.serial = o.String("serial");
  if (o.ok() && v.serial.empty()) o.Fail("serial", "is empty");
  if (o.Has("lights")) {
    const JsonObject levels = o.Object("lights");
    for (const std::string& name : levels.Keys())
      v.lights[name] = levels.Number(name, {.min = 0, .max = 1});
  }
  HR_RETURN_IF_ERROR(o.status());
  return v;
}

std::string PlannedViewRecord::Describe() const {
  char angle[32];
  std::snprintf(angle, sizeof angle, "%.6g", angle_deg);
  std::string text = "view " + std::to_string(view) + " (stop " + std::to_string(stop) + " at " +
                     angle + " deg, camera " + camera + " " + serial + ", lights";
  for (const auto& [name, level] : lights) {
    char value[32];
    std::snprintf(value, sizeof value, "%.6g", level);
    text += " " + name + "=" + value;
  }
  return text + ")";
}

Result<PositionRecord> PositionRecord::FromJson(const nlohmann::json& j, const std::string& where) {
  const JsonObject o(j, where);
  PositionRecord p;
  p.commanded_deg = o.Number("commanded_deg");
  p.measured_deg = o.Number("measured_deg");
  p.time_utc = o.StringOr("time_utc", "");
  HR_RETURN_IF_ERROR(o.status());
  return p;
}

}  // namespace hairrig
