// Camera pose from points on a plane, in normalised image coordinates (a
// pinhole camera with unit focal length: x / z, y / z of the point in the
// camera frame; undistort pixels first). Both functions use fixed-size Eigen
// arithmetic only, so the same input gives the same bits in any process
// (OpenCV's solvePnP results vary in the last digits with the process's
// memory layout, which made a capture calibrate differently from another
// folder).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/transform.h"

namespace hairrig {

// The two poses (cam_from_model) of a planar quadrilateral seen by a pinhole
// camera: Infinitesimal Plane-based Pose Estimation (Collins & Bartoli, IJCV
// 2014), which OpenCV exposes as SOLVEPNP_IPPE. The homography from the
// plane to the image gives the perspective map's Jacobian at the corners'
// centroid; a rotation is recovered from it up to the plane's two-fold
// ambiguity, and each rotation's translation is the linear least-squares
// solution over the 4 corners. Returns 0, 1 or 2 poses, the one with the
// smaller reprojection error first: a pose that puts the tag behind the
// camera (as both do for a tag seen nearly edge-on) is left out. Empty when
// a corner is not finite, the corners are not on one plane (relative
// out-of-plane distance above 1e-6) or are degenerate (three corners on one
// line, in the model or in the image).
std::vector<Rigid3d> PlanarSquarePoses(const std::array<Eigen::Vector3d, 4>& corners_model,
                                       const std::array<Eigen::Vector2d, 4>& normalised);

struct PoseRefinement {
  Rigid3d cam_from_model;
  int iterations = 0;
  double rms = 0;  // reprojection RMS in normalised coordinates
};

// Levenberg-Marquardt on the reprojection error of points in normalised
// coordinates, from `start`: rotation updates on the left (angle-axis),
// translation additive. Stops after an accepted step smaller than 1e-14
// (rotation in rad plus translation over max(1 mm, |t|)), when no step
// lowers the cost any more (damping beyond 1e12), or after 100 iterations.
// `points_model` and `normalised` have the same size (at least 3
// non-collinear points; extra entries of the longer one are ignored). A
// start that puts a point behind the camera is returned unchanged with an
// infinite rms.
PoseRefinement RefinePose(const std::vector<Eigen::Vector3d>& points_model,
                          const std::vector<Eigen::Vector2d>& normalised, const Rigid3d& start);

}  // namespace hairrig
