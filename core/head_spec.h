// What a rig knows of the subject's head, in the turntable frame (mm, deg):
// a triangle mesh placed by a pose, or an ellipsoid, and the scalp region hair
// grows from. The geometry behind it is core/head_model.h; the YAML schema
// (a rig config's or a scene's `head:` section) is core/head_config.h.
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/transform.h"

namespace hairrig {

// The part of the head hair grows from (core/head_model.h). Directions are
// seen from `center_turntable_mm`; elevation 0 is level with it, 90 straight up
// (+z); azimuth 0 is `face_dir`, 180 the back of the head.
struct ScalpSpec {
  // False for a scene without `head.scalp`: the wig's own rule (WigOptions'
  // scalp_min_elevation_deg and face cone) places the roots.
  bool defined = false;
  Eigen::Vector3d center_turntable_mm{0, 0, 330};
  Eigen::Vector3d face_dir{0, -1, 0};  // horizontal, unit
  // The hairline: roots lie above this elevation (deg), linear in azimuth
  // between the forehead (0), the temples (45), above the ear (90 to 120) and the nape (180).
  double hairline_front_deg = 38;
  double hairline_temple_deg = 25;
  double hairline_ear_deg = 8;
  double hairline_nape_deg = -28;
  // The parting: a bare line from the front hairline back over the crown to
  // `parting_back_deg` past the vertical, in the plane through the centre
  // that holds face_dir, tilted towards the head's left (+) or right (-) by
  // `parting_offset_deg` (0 = a centre parting). Hair on either side is combed away from it.
  bool parting = true;
  double parting_offset_deg = 0;
  double parting_width_mm = 2.5;
  double parting_back_deg = 10;
};

struct HeadSpec {
  // A triangle mesh (PLY or OBJ, mm) placed by `turntable_from_mesh`; empty
  // for the ellipsoid below.
  std::string mesh_file;
  Rigid3d turntable_from_mesh;
  // The ellipsoid head; with a mesh, a skull-sized ellipsoid that hair
  // dynamics use for contact and the calibration box's clearance check.
  Eigen::Vector3d center_turntable_mm{0, 0, 250};
  Eigen::Vector3d radii_mm{78, 95, 115};
  Eigen::Vector3d albedo{0.80, 0.66, 0.56};  // linear RGB (skin or a mannequin's paint)
  ScalpSpec scalp;
};

}  // namespace hairrig
