// The JSON form of a head (core/head_spec.h), as a simulated capture's ground
// truth records the true head (<capture>/ground_truth/ground_truth.json,
// "head"). Turntable frame, mm and deg, like the spec:
//
//   {"mesh_file": "head_mesh.ply",           // absent for an ellipsoid head; relative to the JSON
//   file's folder
//    "turntable_from_mesh": pose,            // with a mesh only (core/geometry_json.h)
//    "center_turntable_mm": [x, y, z], "radii_mm": [rx, ry, rz], "albedo": [r, g, b],
//    "scalp": {"defined", "center_turntable_mm", "face_dir", "hairline_front_deg",
//    "hairline_temple_deg",
//              "hairline_ear_deg", "hairline_nape_deg", "parting", "parting_offset_deg",
//              "parting_width_mm", "parting_back_deg"}}
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/head_spec.h"
#include "core/status.h"

namespace hairrig {

// Every field of `head`. The mesh is recorded as `mesh_file_as_written` (not
// empty: the name of a copy beside the JSON file, say, or head.mesh_file
// itself); without a mesh (head.mesh_file empty) neither the file nor the
// pose is written.
nlohmann::json HeadSpecToJson(const HeadSpec& head, const std::string& mesh_file_as_written);

// Reads what HeadSpecToJson wrote. A relative mesh_file is resolved against
// `base_dir` (the JSON file's folder); the mesh itself is not read (see
// HeadModel::Build). CorruptData naming `where` (the file and the object's
// field, e.g. ".../ground_truth.json: head") and the member for a member that
// is missing or of the wrong type, a number that is not finite, radii that are
// not positive, a face direction without a horizontal part or a negative
// parting width.
Result<HeadSpec> HeadSpecFromJson(const nlohmann::json& j, const std::string& base_dir,
                                  const std::string& where);

}  // namespace hairrig
