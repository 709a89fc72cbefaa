#include "core/calib_box.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <utility>

#include "core/config.h"
#include "core/file_util.h"

namespace hairrig {

std::array<Eigen::Vector3d, 8> BoxCornerPoints(const Eigen::Vector3d& half) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int c = 0; c < 8; ++c) {
    corners[c] = Eigen::Vector3d((c & 1 ? 1 : -1) * half.x(), (c & 2 ? 1 : -1) * half.y(),
                                 (c & 4 ? 1 : -1) * half.z());
  }
  return corners;
}

std::vector<BoxFace> MakeBoxFaces(const Eigen::Vector3d& size_mm) {
  struct Spec {
    const char* name;
    Eigen::Vector3d normal;
    Eigen::Vector3d down;
  };
  const Spec specs[] = {{"+x", Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ()},
                        {"-x", -Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ()},
                        {"+y", Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ()},
                        {"-y", -Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ()},
                        {"+z", Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitX()},
                        {"-z", -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()}};
  std::vector<BoxFace> faces;
  for (const Spec& s : specs) {
    BoxFace f;
    f.name = s.name;
    f.normal_box = s.normal;
    f.down_box = s.down;
    f.right_box = s.normal.cross(s.down);
    f.center_box_mm = 0.5 * s.normal.cwiseProduct(size_mm);
    f.width_mm = f.right_box.cwiseAbs().dot(size_mm);
    f.height_mm = f.down_box.cwiseAbs().dot(size_mm);
    faces.push_back(f);
  }
  return faces;
}

const BoxTag* CalibBox::FindTag(int id) const {
  for (const auto& t : tags) {
    if (t.id == id) return &t;
  }
  return nullptr;
}

int CalibBox::FaceIndex(const std::string& name) const {
  for (size_t i = 0; i < faces.size(); ++i) {
    if (faces[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

bool CalibBox::AsDrawn() const {
  for (const BoxFace& f : faces)
    if (f.offset_mm != 0 || f.tilt_u_deg != 0 || f.tilt_v_deg != 0) return false;
  for (const BoxTag& t : tags)
    if (t.turn_deg != 0) return false;
  return true;
}

void PlaceTags(CalibBox* box) {
  const double zero[3] = {0, 0, 0};
  for (BoxTag& tag : box->tags) {
    const BoxFace& face = box->faces[static_cast<size_t>(tag.face)];
    const auto at = [&](double a, double b) { return TagPointInBox(face, tag, a, b, zero, zero); };
    tag.center_box_mm = at(0, 0);
    tag.right_box = (at(1, 0) - tag.center_box_mm).normalized();
    tag.down_box = (at(0, 1) - tag.center_box_mm).normalized();
    for (size_t k = 0; k < 4; ++k) {
      tag.corners_box_mm[k] =
          at(kTagCornerSigns[k][0] * 0.5 * tag.size_mm, kTagCornerSigns[k][1] * 0.5 * tag.size_mm);
    }
  }
}

bool BoxTolerance::Zero() const {
  return tag_center_mm == 0 && tag_turn_deg == 0 && face_offset_mm == 0 && face_tilt_deg == 0;
}

double BoxTolerance::CornerMm(double tag_size_mm, double face_radius_mm) const {
  constexpr double kRad = 3.14159265358979323846 / 180;
  const double turn = tag_turn_deg * kRad * tag_size_mm / std::sqrt(2.0);
  const double tilt = face_tilt_deg * kRad * face_radius_mm;
  return std::sqrt(tag_center_mm * tag_center_mm + turn * turn + face_offset_mm * face_offset_mm +
                   tilt * tilt);
}

Status BoxTolerance::Check() const {
  const std::pair<const char*, double> fields[] = {{"tag_center_mm", tag_center_mm},
                                                   {"tag_turn_deg", tag_turn_deg},
                                                   {"face_offset_mm", face_offset_mm},
                                                   {"face_tilt_deg", face_tilt_deg}};
  for (const auto& [name, value] : fields) {
    // A box off its drawing by more than 50 mm or 45 deg is not the drawn box.
    const double limit = std::string(name).find("deg") != std::string::npos ? 45 : 50;
    if (!(value >= 0 && value <= limit)) {
      return InvalidArgument(std::string(name) + " must be between 0 and " +
                             std::to_string(static_cast<int>(limit)) + ", got " +
                             std::to_string(value));
    }
  }
  return Status::Ok();
}

CalibBox BuildBoxWithErrors(const CalibBox& drawn, const BoxTolerance& spread, uint64_t seed) {
  CalibBox built = drawn;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (BoxFace& face : built.faces) {
    face.offset_mm += spread.face_offset_mm * gauss(rng);
    face.tilt_u_deg += spread.face_tilt_deg * gauss(rng);
    face.tilt_v_deg += spread.face_tilt_deg * gauss(rng);
  }
  for (BoxTag& tag : built.tags) {
    tag.center_face_mm.x() += spread.tag_center_mm * gauss(rng);
    tag.center_face_mm.y() += spread.tag_center_mm * gauss(rng);
    tag.turn_deg += spread.tag_turn_deg * gauss(rng);
  }
  PlaceTags(&built);
  return built;
}

namespace {

// A hand-built box is off its drawing by millimetres and degrees; a value
// beyond these is a mistake in the file, not a build error.
constexpr NumberRange kBuildOffsetRangeMm{-20, 20};
constexpr NumberRange kBuildAngleRangeDeg{-20, 20};
constexpr NumberRange kBuildSdRange{0, 20};

// A face's optional as-built keys (box_as_built.yaml): offset_mm, tilt_deg
// [about u, about v] and their standard deviations.
void ReadFaceBuild(const ConfigNode& node, BoxFace* face) {
  face->offset_mm = node.Number("offset_mm", 0.0, kBuildOffsetRangeMm);
  if (node.Has("tilt_deg")) {
    const auto tilt = node.Numbers("tilt_deg", 2, kBuildAngleRangeDeg);
    if (tilt.size() == 2) face->tilt_u_deg = tilt[0], face->tilt_v_deg = tilt[1];
  }
  face->offset_sd_mm = node.Number("offset_sd_mm", 0.0, kBuildSdRange);
  face->tilt_sd_deg = node.Number("tilt_sd_deg", 0.0, kBuildSdRange);
}

// A tag's optional as-built keys: turn_deg and the standard deviations.
void ReadTagBuild(const ConfigNode& node, BoxTag* tag) {
  tag->turn_deg = node.Number("turn_deg", 0.0, kBuildAngleRangeDeg);
  if (node.Has("center_sd_mm")) {
    const auto sd = node.Numbers("center_sd_mm", 2, kBuildSdRange);
    if (sd.size() == 2) tag->center_sd_mm = {sd[0], sd[1]};
  }
  tag->turn_sd_deg = node.Number("turn_sd_deg", 0.0, kBuildSdRange);
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", value);
  return text;
}

// A standard deviation as written: an unknown one (NaN) is written as 0.
std::string Stddev(double value) { return Number(std::isfinite(value) ? value : 0.0); }

}  // namespace

std::string CalibBoxYaml(const CalibBox& box, const std::string& comment) {
  std::string text;
  size_t from = 0;
  while (from < comment.size()) {
    const size_t end = std::min(comment.find('\n', from), comment.size());
    text += "# " + comment.substr(from, end - from) + "\n";
    from = end + 1;
  }
  text += "family: " + box.family + "\n";
  text += "size_mm: [" + Number(box.size_mm.x()) + ", " + Number(box.size_mm.y()) + ", " +
          Number(box.size_mm.z()) + "]\n";
  text += "faces:\n";
  for (size_t f = 0; f < box.faces.size(); ++f) {
    const BoxFace& face = box.faces[f];
    std::string tags;
    for (const BoxTag& tag : box.tags) {
      if (tag.face != static_cast<int>(f)) continue;
      tags += "      - {id: " + std::to_string(tag.id) + ", size_mm: " + Number(tag.size_mm) +
              ", center_mm: [" + Number(tag.center_face_mm.x()) + ", " +
              Number(tag.center_face_mm.y()) + "], turn_deg: " + Number(tag.turn_deg) +
              ", center_sd_mm: [" + Stddev(tag.center_sd_mm.x()) + ", " +
              Stddev(tag.center_sd_mm.y()) + "], turn_sd_deg: " + Stddev(tag.turn_sd_deg) + "}\n";
    }
    if (tags.empty()) continue;
    text += "  - name: \"" + face.name + "\"\n";
    text += "    offset_mm: " + Number(face.offset_mm) + "\n";
    text += "    tilt_deg: [" + Number(face.tilt_u_deg) + ", " + Number(face.tilt_v_deg) + "]\n";
    text += "    offset_sd_mm: " + Stddev(face.offset_sd_mm) + "\n";
    text += "    tilt_sd_deg: " + Stddev(face.tilt_sd_deg) + "\n";
    text += "    tags:\n" + tags;
  }
  return text;
}

Status WriteCalibBox(const CalibBox& box, const std::string& path, const std::string& comment) {
  return WriteFileAtomic(path, CalibBoxYaml(box, comment));
}

Result<CalibBox> LoadCalibBox(const std::string& path) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  root.AllowOnlyKeys({"family", "size_mm", "tag_size_mm", "faces"});
  CalibBox box;
  box.family = root.Choice("family", {"tag36h11"}, "tag36h11");
  // A calibration box and its tags are well under 10 m.
  const auto size = root.Numbers("size_mm", 3, {.min = 0, .max = 1e4});
  if (size.size() == 3) box.size_mm = {size[0], size[1], size[2]};
  if (root.ok() && box.size_mm.minCoeff() <= 0) root.Fail("size_mm", "every edge must be positive");
  const double default_tag_size = root.Number("tag_size_mm", 0.0, {.min = 1e-3, .max = 1e4});
  box.faces = MakeBoxFaces(box.size_mm);
  std::set<int> ids;
  for (const ConfigNode& face_node : root.Items("faces")) {
    face_node.AllowOnlyKeys(
        {"name", "tags", "offset_mm", "tilt_deg", "offset_sd_mm", "tilt_sd_deg"});
    const std::string face_name = face_node.Choice("name", {"+x", "-x", "+y", "-y", "+z", "-z"});
    const int face_index = box.FaceIndex(face_name);
    if (face_index < 0) continue;
    BoxFace& face = box.faces[static_cast<size_t>(face_index)];
    ReadFaceBuild(face_node, &face);
    for (const ConfigNode& tag_node : face_node.Items("tags")) {
      tag_node.AllowOnlyKeys(
          {"id", "center_mm", "size_mm", "turn_deg", "center_sd_mm", "turn_sd_deg"});
      BoxTag tag;
      tag.id = tag_node.Integer("id", {.min = 0, .max = 586});  // tag36h11 has ids 0-586
      tag.face = face_index;
      tag.size_mm = tag_node.Number("size_mm", default_tag_size, {.min = 1e-3, .max = 1e4});
      const auto c = tag_node.Numbers("center_mm", 2);
      if (!root.ok()) break;
      if (tag.size_mm <= 0) {
        tag_node.Fail("size_mm", "no tag size: give size_mm here or tag_size_mm at the top");
        break;
      }
      tag.center_face_mm = {c[0], c[1]};
      ReadTagBuild(tag_node, &tag);
      // The printed tag is 10/8 of the black border (one white cell around it).
      const double half_printed = 0.5 * tag.size_mm * 10.0 / 8.0;
      if (std::abs(c[0]) + half_printed > 0.5 * face.width_mm + 1e-9 ||
          std::abs(c[1]) + half_printed > 0.5 * face.height_mm + 1e-9) {
        tag_node.Fail("center_mm",
                      "the tag (with its white border) does not fit on face " + face_name);
        break;
      }
      if (!ids.insert(tag.id).second) {
        tag_node.Fail("id", "tag id " + std::to_string(tag.id) + " is used twice on the box");
        break;
      }
      box.tags.push_back(tag);
    }
  }
  if (!root.ok()) return root.status();
  if (box.tags.empty()) return InvalidArgument(path + ": the box has no tags");
  PlaceTags(&box);
  return box;
}

}  // namespace hairrig
