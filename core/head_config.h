// The YAML schema of a head (core/head_spec.h), shared by a rig config's
// `head:` section and a scene's:
//
//   head:
//     mesh: heads/mannequin_head.ply   # optional; relative to the YAML file
//     mesh_pose: {rotation_deg: [rx, ry, rz], translation_mm: [x, y, z]}
//     center_mm: [x, y, z]             # the skull-sized ellipsoid (the head
//     radii_mm: [rx, ry, rz]           #   itself when there is no mesh)
//     albedo: [r, g, b]
//     scalp: {center_mm, face_dir, hairline_front_deg, hairline_temple_deg,
//             hairline_ear_deg, hairline_nape_deg, parting, parting_offset_deg,
//             parting_width_mm, parting_back_deg}
//
// A head section may instead be a string: the path of a YAML file whose
// top-level `head:` is such a map (so a rig config and its scenes can share
// one head file).
#pragma once

#include <string>

#include "core/config.h"
#include "core/head_spec.h"
#include "core/transform.h"

namespace hairrig {

// `relative` resolved against the folder of `base_file` (absolute paths and
// "" unchanged).
std::string ResolveBesideFile(const std::string& base_file, const std::string& relative);

// {rotation_deg: [rx, ry, rz], translation_mm: [x, y, z]}: R = Rz * Ry * Rx.
// Errors are recorded in the node's document.
Rigid3d ReadPoseConfig(const ConfigNode& node);

// Reads `parent`'s field `key` (a head map, or a string naming a head file)
// into `head`, whose values are the defaults for missing fields. Relative
// paths resolve against the folder of `base_file` (the file `parent` came
// from, or the folder its relative paths are relative to). Errors name the
// file, line and field (of the parent's document, or of the head file).
Status ReadHeadConfig(const ConfigNode& parent, const std::string& key,
                      const std::string& base_file, HeadSpec* head);

// A head file: a YAML document with a top-level `head:` map.
Result<HeadSpec> LoadHeadFile(const std::string& path);

// A head file's text (the schema above, every field; lengths and angles to
// 0.01 mm or deg, albedo to 4 decimals, face_dir to 6): what LoadHeadFile
// reads back. A mesh is written by its absolute path.
std::string HeadSpecToYaml(const HeadSpec& head);

// Writes HeadSpecToYaml(head) to `path` atomically. IoError naming the path.
Status WriteHeadFile(const std::string& path, const HeadSpec& head);

// The `head:` of any YAML file that may have one (a scene, a rig config),
// its other top-level keys not read; HeadSpec's defaults when it has none.
Result<HeadSpec> ReadHeadOfFile(const std::string& path);

}  // namespace hairrig
