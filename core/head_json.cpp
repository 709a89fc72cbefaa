#include "core/head_json.h"

#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "core/geometry_json.h"

namespace hairrig {
namespace {

// The geometry readers' InvalidArgument as what a damaged file is.
Status AsCorrupt(const Status& s) { return s.ok() ? s : CorruptData(s.message()); }

Status ReadVector(const nlohmann::json& j, const char* key, const std::string& where, Eigen::Vector3d* out) {
  Result<Eigen::Vector3d> v = Vector3FromJson(j, key, where);
  if (!v.ok()) return AsCorrupt(v.status());
  *out = *v;
  return Status::Ok();
}

Status ReadNumber(const nlohmann::json& j, const char* key, const std::string& where, double* out) {
  if (!j.contains(key) || !j.at(key).is_number() || !std::isfinite(j.at(key).get<double>()))
    return CorruptData(where + ": " + key + " is missing or not a finite number");
  *out = j.at(key).get<double>();
  return Status::Ok();
}

Status ReadBool(const nlohmann::json& j, const char* key, const std::string& where, bool* out) {
  if (!j.contains(key) || !j.at(key).is_boolean()) return CorruptData(where + ": " + key + " is missing or not true/false");
  *out = j.at(key).get<bool>();
  return Status::Ok();
}

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

Status ReadScalp(const nlohmann::json& j, const std::string& where, ScalpSpec* s) {
  if (!j.is_object()) return CorruptData(where + " is not an object");
  HR_RETURN_IF_ERROR(ReadBool(j, "defined", where, &s->defined));
  HR_RETURN_IF_ERROR(ReadVector(j, "center_turntable_mm", where, &s->center_turntable_mm));
  HR_RETURN_IF_ERROR(ReadVector(j, "face_dir", where, &s->face_dir));
  if (Eigen::Vector2d(s->face_dir.x(), s->face_dir.y()).norm() < 1e-9)
    return CorruptData(where + ": face_dir has no horizontal part");
  HR_RETURN_IF_ERROR(ReadNumber(j, "hairline_front_deg", where, &s->hairline_front_deg));
  HR_RETURN_IF_ERROR(ReadNumber(j, "hairline_temple_deg", where, &s->hairline_temple_deg));
  HR_RETURN_IF_ERROR(ReadNumber(j, "hairline_ear_deg", where, &s->hairline_ear_deg));
  HR_RETURN_IF_ERROR(ReadNumber(j, "hairline_nape_deg", where, &s->hairline_nape_deg));
  HR_RETURN_IF_ERROR(ReadBool(j, "parting", where, &s->parting));
  HR_RETURN_IF_ERROR(ReadNumber(j, "parting_offset_deg", where, &s->parting_offset_deg));
  HR_RETURN_IF_ERROR(ReadNumber(j, "parting_width_mm", where, &s->parting_width_mm));
  if (s->parting_width_mm < 0) return CorruptData(where + ": parting_width_mm is negative");
  HR_RETURN_IF_ERROR(ReadNumber(j, "parting_back_deg", where, &s->parting_back_deg));
  return Status::Ok();
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

Result<HeadSpec> HeadSpecFromJson(const nlohmann::json& j, const std::string& base_dir, const std::string& where) {
  if (!j.is_object()) return CorruptData(where + " is not an object");
  HeadSpec head;
  if (j.contains("mesh_file")) {
    const nlohmann::json& file = j.at("mesh_file");
    if (!file.is_string() || file.get<std::string>().empty())
      return CorruptData(where + ": mesh_file is not a file name");
    const std::filesystem::path path(file.get<std::string>());
    head.mesh_file =
        path.is_absolute() ? path.string() : (std::filesystem::path(base_dir) / path).lexically_normal().string();
    Result<Rigid3d> pose = PoseFromJson(j.value("turntable_from_mesh", nlohmann::json()), where + ": turntable_from_mesh");
    if (!pose.ok()) return AsCorrupt(pose.status());
    head.turntable_from_mesh = *pose;
  }
  HR_RETURN_IF_ERROR(ReadVector(j, "center_turntable_mm", where, &head.center_turntable_mm));
  HR_RETURN_IF_ERROR(ReadVector(j, "radii_mm", where, &head.radii_mm));
  if (head.radii_mm.minCoeff() <= 0) return CorruptData(where + ": radii_mm must all be positive");
  HR_RETURN_IF_ERROR(ReadVector(j, "albedo", where, &head.albedo));
  if (!j.contains("scalp")) return CorruptData(where + ": scalp is missing");
  HR_RETURN_IF_ERROR(ReadScalp(j.at("scalp"), where + ".scalp", &head.scalp));
  return head;
}

}  // namespace hairrig
