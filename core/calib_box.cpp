#include "core/calib_box.h"

#include <cmath>
#include <set>

#include "core/config.h"

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

namespace {
void PlaceTag(const BoxFace& face, BoxTag* tag) {
  tag->center_box_mm = face.center_box_mm + tag->center_face_mm.x() * face.right_box +
                       tag->center_face_mm.y() * face.down_box;
  for (int k = 0; k < 4; ++k) {
    tag->corners_box_mm[k] = tag->center_box_mm + 0.5 * tag->size_mm *
                                                      (kTagCornerSigns[k][0] * face.right_box +
                                                       kTagCornerSigns[k][1] * face.down_box);
  }
}
}  // namespace

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
    face_node.AllowOnlyKeys({"name", "tags"});
    const std::string face_name = face_node.Choice("name", {"+x", "-x", "+y", "-y", "+z", "-z"});
    const int face_index = box.FaceIndex(face_name);
    if (face_index < 0) continue;
    const BoxFace& face = box.faces[face_index];
    for (const ConfigNode& tag_node : face_node.Items("tags")) {
      tag_node.AllowOnlyKeys({"id", "center_mm", "size_mm"});
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
      PlaceTag(face, &tag);
      box.tags.push_back(tag);
    }
  }
  if (!root.ok()) return root.status();
  if (box.tags.empty()) return InvalidArgument(path + ": the box has no tags");
  return box;
}

}  // namespace hairrig
