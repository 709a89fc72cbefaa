#include "core/head_config.h"

#include <Eigen/Geometry>
#include <filesystem>
#include <sstream>

#include "core/file_util.h"

namespace hairrig {
namespace {

void ReadScalp(const ConfigNode& n, ScalpSpec* s) {
  n.AllowOnlyKeys({"center_mm", "face_dir", "hairline_front_deg", "hairline_temple_deg",
                   "hairline_ear_deg", "hairline_nape_deg", "parting", "parting_offset_deg",
                   "parting_width_mm", "parting_back_deg"});
  s->defined = true;
  s->center_turntable_mm = n.Vec3("center_mm", s->center_turntable_mm, kPositionRangeMm);
  Eigen::Vector3d face = n.Vec3("face_dir", s->face_dir, kDirectionRange);
  face.z() = 0;
  if (face.norm() < 1e-9)
    n.Fail("face_dir", "must have a horizontal part (x, y): the way the face looks");
  s->face_dir = face.norm() > 0 ? Eigen::Vector3d(face.normalized()) : s->face_dir;
  s->hairline_front_deg =
      n.Number("hairline_front_deg", s->hairline_front_deg, {.min = -90, .max = 90});
  s->hairline_temple_deg =
      n.Number("hairline_temple_deg", s->hairline_temple_deg, {.min = -90, .max = 90});
  s->hairline_ear_deg = n.Number("hairline_ear_deg", s->hairline_ear_deg, {.min = -90, .max = 90});
  s->hairline_nape_deg =
      n.Number("hairline_nape_deg", s->hairline_nape_deg, {.min = -90, .max = 90});
  s->parting = n.Bool("parting", s->parting);
  s->parting_offset_deg =
      n.Number("parting_offset_deg", s->parting_offset_deg, {.min = -60, .max = 60});
  s->parting_width_mm = n.Number("parting_width_mm", s->parting_width_mm, {.min = 0, .max = 50});
  s->parting_back_deg = n.Number("parting_back_deg", s->parting_back_deg, {.min = -90, .max = 90});
}

void ReadHeadMap(const ConfigNode& h, const std::string& base_file, HeadSpec* head) {
  h.AllowOnlyKeys({"mesh", "mesh_pose", "center_mm", "radii_mm", "albedo", "scalp"});
  if (h.Has("mesh")) {
    head->mesh_file = ResolveBesideFile(base_file, h.String("mesh"));
    if (h.Has("mesh_pose")) head->turntable_from_mesh = ReadPoseConfig(h.Child("mesh_pose"));
  }
  head->center_turntable_mm = h.Vec3("center_mm", head->center_turntable_mm, kPositionRangeMm);
  // A head (or a stand-in for one) is well within a metre.
  head->radii_mm = h.Vec3("radii_mm", head->radii_mm, {.min = 0, .max = 1e3});
  if (h.ok() && head->radii_mm.minCoeff() <= 0) h.Fail("radii_mm", "every radius must be positive");
  head->albedo = h.Vec3("albedo", head->albedo, kUnitRange);
  head->scalp.center_turntable_mm = head->center_turntable_mm;
  if (h.Has("scalp")) ReadScalp(h.Child("scalp"), &head->scalp);
}

std::string NumberYaml(double x, int decimals = 2) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << x;
  return out.str();
}

std::string Vec3Yaml(const Eigen::Vector3d& v, int decimals = 2) {
  return "[" + NumberYaml(v.x(), decimals) + ", " + NumberYaml(v.y(), decimals) + ", " +
         NumberYaml(v.z(), decimals) + "]";
}

// A single-quoted YAML scalar: every ' doubled, nothing else escaped.
std::string QuotedYaml(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return quoted + "'";
}

// rotation_deg [rx, ry, rz] with R = Rz * Ry * Rx (ReadPoseConfig's order).
Eigen::Vector3d RotationDeg(const Rigid3d& pose) {
  const Eigen::Vector3d zyx = pose.RotationMatrix().eulerAngles(2, 1, 0);
  return Eigen::Vector3d(RadToDeg(zyx[2]), RadToDeg(zyx[1]), RadToDeg(zyx[0]));
}

}  // namespace

std::string HeadSpecToYaml(const HeadSpec& head) {
  std::ostringstream out;
  out << "head:\n";
  if (!head.mesh_file.empty()) {
    out << "  mesh: " << QuotedYaml(std::filesystem::absolute(head.mesh_file).string()) << "\n"
        << "  mesh_pose:\n"
        << "    rotation_deg: " << Vec3Yaml(RotationDeg(head.turntable_from_mesh)) << "\n"
        << "    translation_mm: " << Vec3Yaml(head.turntable_from_mesh.translation) << "\n";
  }
  out << "  center_mm: " << Vec3Yaml(head.center_turntable_mm) << "\n"
      << "  radii_mm: " << Vec3Yaml(head.radii_mm) << "\n"
      << "  albedo: " << Vec3Yaml(head.albedo, 4) << "\n";
  const ScalpSpec& s = head.scalp;
  if (s.defined) {
    out << "  scalp:\n"
        << "    center_mm: " << Vec3Yaml(s.center_turntable_mm) << "\n"
        << "    face_dir: " << Vec3Yaml(s.face_dir, 6) << "\n"
        << "    hairline_front_deg: " << NumberYaml(s.hairline_front_deg) << "\n"
        << "    hairline_temple_deg: " << NumberYaml(s.hairline_temple_deg) << "\n"
        << "    hairline_ear_deg: " << NumberYaml(s.hairline_ear_deg) << "\n"
        << "    hairline_nape_deg: " << NumberYaml(s.hairline_nape_deg) << "\n"
        << "    parting: " << (s.parting ? "true" : "false") << "\n"
        << "    parting_offset_deg: " << NumberYaml(s.parting_offset_deg) << "\n"
        << "    parting_width_mm: " << NumberYaml(s.parting_width_mm) << "\n"
        << "    parting_back_deg: " << NumberYaml(s.parting_back_deg) << "\n";
  }
  return out.str();
}

Status WriteHeadFile(const std::string& path, const HeadSpec& head) {
  return WriteFileAtomic(path, HeadSpecToYaml(head));
}

std::string ResolveBesideFile(const std::string& base_file, const std::string& relative) {
  if (relative.empty() || relative[0] == '/') return relative;
  return (std::filesystem::path(base_file).parent_path() / relative).lexically_normal().string();
}

Rigid3d ReadPoseConfig(const ConfigNode& n) {
  n.AllowOnlyKeys({"translation_mm", "rotation_deg"});
  const Eigen::Vector3d t = n.Vec3("translation_mm", Eigen::Vector3d::Zero(), kPositionRangeMm);
  const Eigen::Vector3d r = n.Vec3("rotation_deg", Eigen::Vector3d::Zero(), kRotationRangeDeg);
  const Eigen::Quaterniond q = Eigen::AngleAxisd(DegToRad(r.z()), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(DegToRad(r.y()), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(DegToRad(r.x()), Eigen::Vector3d::UnitX());
  return Rigid3d(q, t);
}

Status ReadHeadConfig(const ConfigNode& parent, const std::string& key,
                      const std::string& base_file, HeadSpec* head) {
  if (parent.HasScalar(key)) {
    const std::string file = ResolveBesideFile(base_file, parent.String(key));
    Result<HeadSpec> from_file = LoadHeadFile(file);
    if (!from_file.ok())
      return from_file.status().WithContext(parent.Where() + ": field '" + key + "'");
    *head = *from_file;
    return Status::Ok();
  }
  ReadHeadMap(parent.Child(key), base_file, head);
  return parent.status();
}

Result<HeadSpec> LoadHeadFile(const std::string& path) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  root.AllowOnlyKeys({"head"});
  HeadSpec head;
  if (root.HasScalar("head"))
    root.Fail("head", "a head file's head must be a map, not another file's name");
  if (root.ok()) ReadHeadMap(root.Child("head"), path, &head);
  HR_RETURN_IF_ERROR(root.status());
  return head;
}

Result<HeadSpec> ReadHeadOfFile(const std::string& path) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  HeadSpec head;
  if (root.Has("head")) HR_RETURN_IF_ERROR(ReadHeadConfig(root, "head", path, &head));
  return head;
}

}  // namespace hairrig
