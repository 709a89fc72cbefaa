// For tests: a centred pinhole camera, and an analytic scene for the stereo and the fusion, a plane
// of strands (z = 0 in the object frame, 180 mm square) whose direction turns across it, seen by
// four cameras on an arc 600 mm away. The orientation maps and the grey images are exact
// projections; the true depth of each pixel is kept beside them.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "reconstruction/line_mvs.h"

namespace hairrig::plane_scene {

inline constexpr int kSceneWidth = 240, kSceneHeight = 200;

// Strand direction on the plane z = 0 (object frame) at (x, y) mm.
inline double StrandAngle(double x, double y) { return 0.03 * x + 0.02 * y + 0.0004 * x * y; }

// Wavy strands instead, y = c + 6 sin(2 pi x / 40) mm: the direction swings
// by up to 43 deg either way within a 40 mm wave (27 px in the views).
inline double WavyStrandAngle(double x, double /*y*/) {
  constexpr double kAmplitudeMm = 6, kWaveNumber = 2 * 3.14159265358979 / 40;
  return std::atan(kAmplitudeMm * kWaveNumber * std::cos(kWaveNumber * x));
}

using StrandAngleFn = double (*)(double x, double y);

struct PlaneScene {
  std::vector<MvsView> views;
  std::vector<cv::Mat1f> true_depth;
};

// A pinhole camera with its principal point at the image centre.
inline CameraIntrinsics CentredCamera(int width_px, int height_px, double focal_px) {
  CameraIntrinsics camera;
  camera.width_px = width_px;
  camera.height_px = height_px;
  camera.fx_px = camera.fy_px = focal_px;
  camera.cx_px = width_px / 2.0 - 0.5;
  camera.cy_px = height_px / 2.0 - 0.5;
  return camera;
}

inline MvsView RenderPlane(double azimuth_deg, cv::Mat1f* true_depth,
                           StrandAngleFn strand_angle = StrandAngle) {
  MvsView v;
  v.camera = CentredCamera(kSceneWidth, kSceneHeight, 400);
  v.camera.k1 = -0.02;
  const double a = DegToRad(azimuth_deg);
  const Eigen::Vector3d eye(600 * std::sin(a), -100, -600 * std::cos(a));
  v.cam_from_object = LookAt(eye, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY());
  v.grey = cv::Mat1f(kSceneHeight, kSceneWidth, 0.f);
  v.orientation_deg = cv::Mat1f(kSceneHeight, kSceneWidth, std::numeric_limits<float>::quiet_NaN());
  v.hair = cv::Mat1b(kSceneHeight, kSceneWidth, uint8_t{0});
  *true_depth = cv::Mat1f(kSceneHeight, kSceneWidth, 0.f);
  const Rigid3d object_from_cam = v.cam_from_object.Inverse();
  for (int y = 0; y < kSceneHeight; ++y) {
    for (int x = 0; x < kSceneWidth; ++x) {
      const Result<Eigen::Vector2d> n = UndistortPixel(v.camera, Eigen::Vector2d(x, y));
      if (!n.ok()) continue;
      const Eigen::Vector3d origin = object_from_cam.translation;
      const Eigen::Vector3d dir = object_from_cam.rotation * Eigen::Vector3d(n->x(), n->y(), 1);
      const double s = -origin.z() / dir.z();
      const Eigen::Vector3d p = origin + s * dir;
      if (std::abs(p.x()) > 90 || std::abs(p.y()) > 90) continue;
      const double psi = strand_angle(p.x(), p.y());
      const Eigen::Vector3d t(std::cos(psi), std::sin(psi), 0);
      const Eigen::Vector2d uv0 = Project(v.camera, v.cam_from_object * p);
      const Eigen::Vector2d uv1 = Project(v.camera, v.cam_from_object * (p + 0.1 * t));
      double angle = RadToDeg(std::atan2(uv1.y() - uv0.y(), uv1.x() - uv0.x()));
      if (angle < 0) angle += 180;
      if (angle >= 180) angle -= 180;
      v.orientation_deg(y, x) = static_cast<float>(angle);
      v.hair(y, x) = 255;
      // Stripes across the strands, fixed on the plane: texture for the NCC.
      const double across = -std::sin(psi) * p.x() + std::cos(psi) * p.y();
      v.grey(y, x) =
          static_cast<float>(128 + 60 * std::sin(1.7 * across) + 20 * std::sin(0.31 * p.x()));
      (*true_depth)(y, x) = static_cast<float>((v.cam_from_object * p).z());
    }
  }
  return v;
}

inline PlaneScene MakeScene(StrandAngleFn strand_angle = StrandAngle) {
  PlaneScene scene;
  for (double azimuth : {-20.0, 0.0, 20.0, 40.0}) {
    cv::Mat1f depth;
    scene.views.push_back(RenderPlane(azimuth, &depth, strand_angle));
    scene.true_depth.push_back(depth);
  }
  return scene;
}

// The true unit strand direction at a point of the plane (object frame).
inline Eigen::Vector3d StrandDirection(const Eigen::Vector3d& p) {
  const double psi = StrandAngle(p.x(), p.y());
  return {std::cos(psi), std::sin(psi), 0};
}

}  // namespace hairrig::plane_scene
