// The calibration box: a rigid box with AprilTags on its faces, hung above the
// hair and turning with the turntable (Bao & Qi 2017, Sec. VII-A, with AprilTag
// 36h11 in place of ARTag). Loaded from etc/calib-box.yaml.
//
// Box frame: origin at the box centre, axes along its edges, +z up as hung.
// Each face has an outward normal n and a face frame as seen from outside:
// `right` (u) and `down` (v), with u x v = -n. Side faces (+-x, +-y) have
// down = -z; the bottom face (-z) has down = +x; the top face (+z) down = -x.
// A tag's position is its centre in (u, v) on the face, in mm from the face centre.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// Corner k of a tag, as libapriltag reports detection corners p[k], sits at
// (sign_u * s/2, sign_v * s/2) in the face frame (s = tag size): bottom-left,
// bottom-right, top-right, top-left as seen from outside the box.
constexpr std::array<std::array<int, 2>, 4> kTagCornerSigns = {
    {{-1, +1}, {+1, +1}, {+1, -1}, {-1, -1}}};

struct BoxFace {
  std::string name;                                      // "+x", "-x", "+y", "-y", "+z", "-z"
  Eigen::Vector3d normal_box = Eigen::Vector3d::Zero();  // outward
  Eigen::Vector3d right_box = Eigen::Vector3d::Zero();   // u
  Eigen::Vector3d down_box = Eigen::Vector3d::Zero();    // v
  Eigen::Vector3d center_box_mm = Eigen::Vector3d::Zero();
  double width_mm = 0;   // extent along u
  double height_mm = 0;  // extent along v
};

struct BoxTag {
  int id = -1;
  int face = -1;                                             // index into CalibBox::faces
  double size_mm = 0;                                        // edge of the black border square
  Eigen::Vector2d center_face_mm = Eigen::Vector2d::Zero();  // (u, v)
  Eigen::Vector3d center_box_mm = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 4> corners_box_mm;  // in kTagCornerSigns order
};

struct CalibBox {
  std::string family = "tag36h11";
  Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();  // edge lengths along box x, y, z
  std::vector<BoxFace> faces;                         // all six
  std::vector<BoxTag> tags;

  const BoxTag* FindTag(int id) const;
  int FaceIndex(const std::string& name) const;  // -1 if unknown
};

// Errors name the file, line and field: unknown face, duplicate id, a tag that
// leaves its face, non-positive sizes.
Result<CalibBox> LoadCalibBox(const std::string& path);

// The eight corners (+-half.x, +-half.y, +-half.z) of a box centred at the origin.
std::array<Eigen::Vector3d, 8> BoxCornerPoints(const Eigen::Vector3d& half_size_mm);

// The six faces of a box of the given size, in the convention above.
std::vector<BoxFace> MakeBoxFaces(const Eigen::Vector3d& size_mm);

}  // namespace hairrig
