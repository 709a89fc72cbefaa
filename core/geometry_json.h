// JSON forms of the geometry types, shared by every file that stores poses or
// intrinsics (ground truth, calibration.json). Frames as in core/transform.h;
// millimetres and pixels.
//
//   pose:       {"quaternion_wxyz": [w,x,y,z], "translation_mm": [x,y,z], "matrix_3x4":
//   [[..],[..],[..]]} intrinsics: {"width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px",
//   "k1", "k2", "p1", "p2", "k3"} vector:     [x, y, z]
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

class JsonObject;

nlohmann::json PoseToJson(const Rigid3d& a_from_b);
// Reads the quaternion and translation (the matrix is for people reading the
// file). InvalidArgument names `where` (file and field) when a member is
// missing, not a number, not finite, or the quaternion is far from unit.
Result<Rigid3d> PoseFromJson(const nlohmann::json& j, const std::string& where);

nlohmann::json IntrinsicsToJson(const CameraIntrinsics& camera);
// InvalidArgument names `where` and the member; the result passes CameraIntrinsics::Check().
Result<CameraIntrinsics> IntrinsicsFromJson(const nlohmann::json& j, const std::string& where);

nlohmann::json Vector3ToJson(const Eigen::Vector3d& v);
// j[key] as three finite numbers. InvalidArgument names `where` and the key
// when it is missing, not three numbers, or not finite.
Result<Eigen::Vector3d> Vector3FromJson(const nlohmann::json& j, const std::string& key,
                                        const std::string& where);

// The readers above applied to field `key` of `j` (core/json_file.h): a
// problem is recorded in `j` as CorruptData naming the file and the field, and
// a neutral value (identity, default intrinsics, zero) is returned.
Rigid3d PoseField(const JsonObject& j, std::string_view key);
CameraIntrinsics IntrinsicsField(const JsonObject& j, std::string_view key);
Eigen::Vector3d Vector3Field(const JsonObject& j, std::string_view key);

}  // namespace hairrig
