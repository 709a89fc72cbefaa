// Views of a block of hair from its front: cameras at y = 600 mm looking
// down -y at the block's centre, and the block's seen front face as oriented
// points every mm that all of them saw. For tests of what the views see
// through (reconstruction/free_space.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/transform.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/views.h"
#include "tests/support/plane_scene_testing.h"

namespace hairrig::front_views {

// `count` cameras spread along x (every 60 mm) at y = 600, z = `centre_z`,
// each looking at (0, 0, centre_z); 1000 x 1000 px, focal 2000 px (about
// 3.5 px per mm at the block).
inline std::vector<ReconstructionView> Cameras(int count, double centre_z) {
  std::vector<ReconstructionView> views;
  for (int k = 0; k < count; ++k) {
    ReconstructionView v;
    v.id = k;
    v.name = "front" + std::to_string(k);
    v.camera = plane_scene::CentredCamera(1000, 1000, 2000);
    const Eigen::Vector3d eye(60.0 * (k - (count - 1) / 2.0), 600, centre_z);
    v.cam_from_object = LookAt(eye, Eigen::Vector3d(0, 0, centre_z));
    views.push_back(v);
  }
  return views;
}

// The plane y = `front_y` over x in [-half_width, half_width] and z in
// [z_low, z_high], a point every mm, seen by every one of `views` views.
inline std::vector<OrientedPoint> FrontFace(double front_y, double half_width, double z_low,
                                            double z_high, int views) {
  std::vector<OrientedPoint> points;
  std::vector<uint16_t> all;
  for (int k = 0; k < views; ++k) all.push_back(static_cast<uint16_t>(k));
  for (double x = -half_width; x <= half_width; x += 1) {
    for (double z = z_low; z <= z_high; z += 1) {
      OrientedPoint p;
      p.position_mm = Eigen::Vector3f(float(x), float(front_y), float(z));
      p.direction = Eigen::Vector3f(0, 0, 1);
      p.confidence = 1;
      p.views = all;
      points.push_back(p);
    }
  }
  return points;
}

}  // namespace hairrig::front_views
