#include "core/head_json.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/geometry_json.h"
#include "core/json_file.h"

namespace hairrig {
namespace {

nlohmann::json ScalpToJson(const ScalpSpec& s) {
  return {{"defined", s.defined},
          {"center_turntable_mm", Vector3ToJson(s.center_turntable_mm)},
          {"face_dir", Vector3ToJson(s.face_dir)},
          {"hairline_front_deg", s.hairline_front_deg},
          {"hairline_temple_deg", s.hairline_temple_deg},
          {"hairline_ear_deg", s.hairline_ear_deg},
          {"hairline_nape_deg", s.hairline_nape_deg},
          {"parting", s.parting},
          {"parting_offset_deg", s.parting_offset_deg},
          {"parting_width_mm", s.parting_width_mm},
          {"parting_back_deg", s.parting_back_deg}};
}

// Errors are recorded in `j`.
ScalpSpec ScalpFromJson(const JsonObject& j) {
  ScalpSpec s;
  s.defined = j.Bool("defined");
  s.center_turntable_mm = Vector3Field(j, "center_turntable_mm");
  s.face_dir = Vector3Field(j, "face_dir");
  if (j.ok() && Eigen::Vector2d(s.face_dir.x(), s.face_dir.y()).norm() < 1e-9)
    j.Fail("face_dir", "has no horizontal part");
  s.hairline_front_deg = j.Number("hairline_front_deg");
  s.hairline_temple_deg = j.Number("hairline_temple_deg");
  s.hairline_ear_deg = j.Number("hairline_ear_deg");
  s.hairline_nape_deg = j.Number("hairline_nape_deg");
  s.parting = j.Bool("parting");
  s.parting_offset_deg = j.Number("parting_offset_deg");
  s.parting_width_mm = j.Number("parting_width_mm", {.min = 0});
  s.parting_back_deg = j.Number("parting_back_deg");
  return s;
}

}  // namespace

nlohmann::json HeadSpecToJson(const HeadSpec& head, const std::string& mesh_file_as_written) {
  nlohmann::json j;
  if (!head.mesh_file.empty()) {
    j["mesh_file"] = mesh_file_as_written;
    j["turntable_from_mesh"] = PoseToJson(head.turntable_from_mesh);
  }
  j["center_turntable_mm"] = Vector3ToJson(head.center_turntable_mm);
  j["radii_mm"] = Vector3ToJson(head.radii_mm);
  j["albedo"] = Vector3ToJson(head.albedo);
  j["scalp"] = ScalpToJson(head.scalp);
  return j;
}

Result<HeadSpec> HeadSpecFromJson(const nlohmann::json& j, const std::string& base_dir,
                                  const std::string& where) {
  const JsonObject o(j, where);
  HeadSpec head;
  if (o.Has("mesh_file")) {
    const std::filesystem::path path(o.String("mesh_file"));
    if (o.ok() && path.empty()) o.Fail("mesh_file", "is empty");
    head.mesh_file = path.is_absolute()
                         ? path.string()
                         : (std::filesystem::path(base_dir) / path).lexically_normal().string();
    head.turntable_from_mesh = PoseField(o, "turntable_from_mesh");
  }
  head.center_turntable_mm = Vector3Field(o, "center_turntable_mm");
  head.radii_mm = Vector3Field(o, "radii_mm");
  if (o.ok() && head.radii_mm.minCoeff() <= 0) o.Fail("radii_mm", "must all be positive");
  head.albedo = Vector3Field(o, "albedo");
  head.scalp = ScalpFromJson(o.Object("scalp"));
  HR_RETURN_IF_ERROR(o.status());
  return head;
}

}  // namespace hairrig
