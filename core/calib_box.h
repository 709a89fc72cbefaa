// The calibration box: a rigid box with AprilTags on its faces, hung above the
// hair and turning with the turntable (Bao & Qi 2017, Sec. VII-A, with AprilTag
// 36h11 in place of ARTag). Loaded from etc/calib-box.yaml (as drawn) or from a
// box_as_built.yaml that a calibration refined (WriteCalibBox).
//
// Box frame: origin at the box centre, axes along its edges, +z up as hung.
// Each face has an outward normal n and a face frame as seen from outside:
// `right` (u) and `down` (v), with u x v = -n. Side faces (+-x, +-y) have
// down = -z; the bottom face (-z) has down = +x; the top face (+z) down = -x.
// A tag's position is its centre in (u, v) on the face, in mm from the face centre.
//
// A box built by hand departs from its drawing (docs/design.md section 5): each
// tag sits off its drawn centre and turned about the face normal; each face
// plane is moved along its normal and tilted about its centre. These are the
// face's offset_mm, tilt_u_deg, tilt_v_deg and the tag's turn_deg below (all 0
// as drawn); TagPointInBox places a tag's points from them, and the bundle
// adjustment differentiates it to refine them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// Corner k of a tag, as libapriltag reports detection corners p[k], sits at
// (sign_u * s/2, sign_v * s/2) in the tag's frame (s = tag size): bottom-left,
// bottom-right, top-right, top-left as seen from outside the box.
constexpr std::array<std::array<int, 2>, 4> kTagCornerSigns = {
    {{-1, +1}, {+1, +1}, {+1, -1}, {-1, -1}}};

struct BoxFace {
  std::string name;                                      // "+x", "-x", "+y", "-y", "+z", "-z"
  Eigen::Vector3d normal_box = Eigen::Vector3d::Zero();  // outward, as drawn
  Eigen::Vector3d right_box = Eigen::Vector3d::Zero();   // u, as drawn
  Eigen::Vector3d down_box = Eigen::Vector3d::Zero();    // v, as drawn
  Eigen::Vector3d center_box_mm = Eigen::Vector3d::Zero();
  double width_mm = 0;   // extent along u
  double height_mm = 0;  // extent along v
  // As built: the plane moved along the outward normal (mm) and turned about
  // its centre, right-handed about u then about v (deg).
  double offset_mm = 0;
  double tilt_u_deg = 0, tilt_v_deg = 0;
  // Their standard deviations where a refinement estimated them (0: unknown).
  double offset_sd_mm = 0, tilt_sd_deg = 0;
};

struct BoxTag {
  int id = -1;
  int face = -1;                                             // index into CalibBox::faces
  double size_mm = 0;                                        // edge of the black border square
  Eigen::Vector2d center_face_mm = Eigen::Vector2d::Zero();  // (u, v) before the face's tilt
  double turn_deg = 0;  // about the face normal, from u towards v
  // Standard deviations of center_face_mm and turn_deg where a refinement
  // estimated them (0: unknown).
  Eigen::Vector2d center_sd_mm = Eigen::Vector2d::Zero();
  double turn_sd_deg = 0;
  // Derived (PlaceTags): where the tag is in the box frame, as built.
  Eigen::Vector3d center_box_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d right_box = Eigen::Vector3d::Zero();  // the tag's own u, unit
  Eigen::Vector3d down_box = Eigen::Vector3d::Zero();   // the tag's own v, unit
  std::array<Eigen::Vector3d, 4> corners_box_mm;        // in kTagCornerSigns order
};

struct CalibBox {
  std::string family = "tag36h11";
  Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();  // edge lengths along box x, y, z
  std::vector<BoxFace> faces;                         // all six
  std::vector<BoxTag> tags;

  const BoxTag* FindTag(int id) const;
  int FaceIndex(const std::string& name) const;  // -1 if unknown
  // True when no face or tag departs from the drawing.
  bool AsDrawn() const;
};

// Point (a, b) mm of a tag's own frame (from its centre along its u and v) in
// the box frame, with the tag moved by tag_delta = (du mm, dv mm, dturn rad)
// in its face and the face by face_delta = (doffset mm, dtilt_u rad, dtilt_v
// rad) from the values `face` and `tag` hold. T is double or a Ceres Jet.
template <typename T>
Eigen::Matrix<T, 3, 1> TagPointInBox(const BoxFace& face, const BoxTag& tag, double a_mm,
                                     double b_mm, const T* face_delta, const T* tag_delta) {
  using std::cos;
  using std::sin;
  constexpr double kRad = 3.14159265358979323846 / 180;
  const T turn = T(tag.turn_deg * kRad) + tag_delta[2];
  const T cos_turn = cos(turn), sin_turn = sin(turn);
  // In the face plane, from the face centre (u, v).
  const T u = T(tag.center_face_mm.x()) + tag_delta[0] + cos_turn * a_mm - sin_turn * b_mm;
  const T v = T(tag.center_face_mm.y()) + tag_delta[1] + sin_turn * a_mm + cos_turn * b_mm;
  // The tilt in the right-handed frame (u, v, w = u x v = -n): about u, then about v.
  const T tilt_u = T(face.tilt_u_deg * kRad) + face_delta[1];
  const T tilt_v = T(face.tilt_v_deg * kRad) + face_delta[2];
  const T v1 = v * cos(tilt_u), w1 = v * sin(tilt_u);
  const T u2 = u * cos(tilt_v) + w1 * sin(tilt_v);
  const T w2 = -u * sin(tilt_v) + w1 * cos(tilt_v);
  const T along_normal = T(face.offset_mm) + face_delta[0] - w2;
  Eigen::Matrix<T, 3, 1> p;
  for (int i = 0; i < 3; ++i) {
    p[i] = T(face.center_box_mm[i]) + along_normal * face.normal_box[i] + u2 * face.right_box[i] +
           v1 * face.down_box[i];
  }
  return p;
}

// Sets every tag's derived fields (centre, axes and corners in the box frame)
// from its face and its own placement.
void PlaceTags(CalibBox* box);

// How far a built box departs from its drawing, as standard deviations
// (build tolerances): tags moved in their face and turned, faces moved along
// their normal and tilted. Used to draw a box as built in the simulator and
// to weigh the drawing in the bundle adjustment's box refinement.
struct BoxTolerance {
  double tag_center_mm = 0;  // per axis of the face
  double tag_turn_deg = 0;
  double face_offset_mm = 0;
  double face_tilt_deg = 0;  // per axis

  bool Zero() const;
  // How far a tag's corners may be off their model from all four, combined
  // (mm, one standard deviation): the tag's move, its turn at a corner of a
  // tag of `tag_size_mm`, the face's offset and its tilt at `face_radius_mm`
  // from the face centre.
  double CornerMm(double tag_size_mm, double face_radius_mm) const;
  // InvalidArgument naming the field for a negative or non-finite value.
  Status Check() const;
};

// What a box glued by hand keeps to (the priors of the calibration's box
// refinement by default): tags within about 1 mm and 1 deg of their drawn
// place, faces within 0.5 mm and 0.3 deg.
inline constexpr BoxTolerance kHandBuiltBoxTolerance{1.0, 1.0, 0.5, 0.3};

// A box as built: every tag and face of `drawn` moved by a Gaussian draw with
// the standard deviations of `spread` from a generator seeded with `seed`
// (the same seed gives the same box on every machine with this libstdc++).
CalibBox BuildBoxWithErrors(const CalibBox& drawn, const BoxTolerance& spread, uint64_t seed);

// Errors name the file, line and field: unknown face, duplicate id, a tag that
// leaves its face, non-positive sizes, build errors beyond 20 mm or 20 deg.
Result<CalibBox> LoadCalibBox(const std::string& path);

// `box` in LoadCalibBox's format: every tag with its size, centre and turn,
// every face that holds a tag with its offset and tilt, and the standard
// deviations; `comment` (lines) opens the text as comments.
std::string CalibBoxYaml(const CalibBox& box, const std::string& comment);
// The same, written atomically to `path`; IoError names the file.
Status WriteCalibBox(const CalibBox& box, const std::string& path, const std::string& comment);

// The eight corners (+-half.x, +-half.y, +-half.z) of a box centred at the origin.
std::array<Eigen::Vector3d, 8> BoxCornerPoints(const Eigen::Vector3d& half_size_mm);

// The six faces of a box of the given size, in the convention above.
std::vector<BoxFace> MakeBoxFaces(const Eigen::Vector3d& size_mm);

}  // namespace hairrig
