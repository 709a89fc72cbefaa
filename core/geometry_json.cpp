#include "core/geometry_json.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/json_file.h"

namespace hairrig {

nlohmann::json PoseToJson(const Rigid3d& a_from_b) {
  const Eigen::Quaterniond& q = a_from_b.rotation;
  const auto mat = a_from_b.ToMatrix3x4();
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({mat(r, 0), mat(r, 1), mat(r, 2), mat(r, 3)});
  const Eigen::Vector3d& t = a_from_b.translation;
  return {{"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}},
          {"translation_mm", {t.x(), t.y(), t.z()}},
          {"matrix_3x4", rows}};
}

namespace {

// A fixed-length array of finite numbers at j[key].
template <size_t N>
Status ReadNumbers(const nlohmann::json& j, const char* key, const std::string& where,
                   double (&out)[N]) {
  const std::string field = where + ": " + key;
  if (!j.is_object() || !j.contains(key)) return InvalidArgument(field + " is missing");
  const nlohmann::json& a = j.at(key);
  if (!a.is_array() || a.size() != N)
    return InvalidArgument(field + " must be " + std::to_string(N) + " numbers");
  for (size_t i = 0; i < N; ++i) {
    if (!a[i].is_number() || !std::isfinite(a[i].get<double>()))
      return InvalidArgument(field + "[" + std::to_string(i) + "] is not a finite number");
    out[i] = a[i].get<double>();
  }
  return Status::Ok();
}

}  // namespace

Result<Rigid3d> PoseFromJson(const nlohmann::json& j, const std::string& where) {
  double q[4], t[3];
  HR_RETURN_IF_ERROR(ReadNumbers(j, "quaternion_wxyz", where, q));
  HR_RETURN_IF_ERROR(ReadNumbers(j, "translation_mm", where, t));
  const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);
  if (std::abs(rotation.norm() - 1) > 1e-6)
    return InvalidArgument(where + ": quaternion_wxyz is not a unit quaternion (norm " +
                           std::to_string(rotation.norm()) + ")");
  return Rigid3d(rotation, Eigen::Vector3d(t[0], t[1], t[2]));
}

nlohmann::json IntrinsicsToJson(const CameraIntrinsics& camera) {
  nlohmann::json j;
  j["width_px"] = camera.width_px;
  j["height_px"] = camera.height_px;
  const auto params = camera.ToParams();
  for (int i = 0; i < CameraIntrinsics::kNumParams; ++i)
    j[CameraIntrinsics::kParamNames[static_cast<size_t>(i)]] = params[static_cast<size_t>(i)];
  return j;
}

Result<CameraIntrinsics> IntrinsicsFromJson(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) return InvalidArgument(where + ": intrinsics must be an object");
  std::array<double, CameraIntrinsics::kNumParams> params{};
  for (int i = 0; i < CameraIntrinsics::kNumParams; ++i) {
    const char* name = CameraIntrinsics::kParamNames[static_cast<size_t>(i)];
    if (!j.contains(name) || !j[name].is_number() || !std::isfinite(j[name].get<double>()))
      return InvalidArgument(where + ": " + name + " is missing or not a finite number");
    params[static_cast<size_t>(i)] = j[name].get<double>();
  }
  for (const char* name : {"width_px", "height_px"}) {
    if (!j.contains(name) || !j[name].is_number_integer())
      return InvalidArgument(where + ": " + name + " is missing or not an integer");
  }
  const CameraIntrinsics camera = CameraIntrinsics::FromParams(
      params.data(), j["width_px"].get<int>(), j["height_px"].get<int>());
  const Status valid = camera.Check();
  if (!valid.ok()) return InvalidArgument(where + ": " + valid.message());
  return camera;
}

nlohmann::json Vector3ToJson(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

Result<Eigen::Vector3d> Vector3FromJson(const nlohmann::json& j, const std::string& key,
                                        const std::string& where) {
  double v[3];
  HR_RETURN_IF_ERROR(ReadNumbers(j, key.c_str(), where, v));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

namespace {

template <typename T>
T FieldOr(const JsonObject& j, const Result<T>& read, T neutral) {
  if (read.ok()) return *read;
  j.Record(read.status());
  return neutral;
}

}  // namespace

Rigid3d PoseField(const JsonObject& j, std::string_view key) {
  return FieldOr(j, PoseFromJson(j.Raw(key), j.Describe(key)), Rigid3d());
}

CameraIntrinsics IntrinsicsField(const JsonObject& j, std::string_view key) {
  return FieldOr(j, IntrinsicsFromJson(j.Raw(key), j.Describe(key)), CameraIntrinsics());
}

Eigen::Vector3d Vector3Field(const JsonObject& j, std::string_view key) {
  const std::vector<double> v = j.Numbers(key, 3);
  return v.size() == 3 ? Eigen::Vector3d(v[0], v[1], v[2]) : Eigen::Vector3d::Zero();
}

}  // namespace hairrig
