// The angle of an undirected image line and the difference of two, for the
// stereo's inner loop (line_mvs.cpp: one per sample and neighbour view of
// every hypothesis), cheaper than std::atan2 and std::fmod.
#pragma once

#include <cmath>

#include "core/transform.h"

namespace hairrig {

// The angle of the line along (dx, dy), in degrees in [0, 180) (image axes:
// x right, y down; the same convention as the orientation maps), within
// 0.00075 deg of the exact angle (line_angle_test.cpp): atan on [0, 1] is an
// odd polynomial of degree 9 (least squares on Chebyshev nodes), its largest
// error 0.0007 deg. It is not exactly monotonic: at 45 and 135 deg it steps
// back by 0.0013 deg, harmless where angles are compared to a tolerance.
// (0, 0) gives 0; NaN gives NaN.
inline double LineAngleDeg(double dx, double dy) {
  if (dy < 0 || (dy == 0 && dx < 0)) {  // the same line, pointing into y >= 0
    dx = -dx;
    dy = -dy;
  }
  const double ax = std::abs(dx);
  if (ax == 0 && dy == 0) return 0;
  const bool steep = dy > ax;
  const double t = steep ? ax / dy : dy / ax;  // in [0, 1]
  const double t2 = t * t;
  double rad = t * (0.99987873 +
                    t2 * (-0.33040532 + t2 * (0.18041155 + t2 * (-0.08540653 + t2 * 0.0209309))));
  if (steep) rad = kPi / 2 - rad;
  if (dx < 0) rad = kPi - rad;
  const double deg = rad * (180.0 / kPi);
  return deg >= 180.0 ? 0.0 : deg;
}

// The difference of two line angles, in degrees in [0, 90] (as
// OrientationDifferenceDeg, without its fmod when both are in [0, 180)).
inline double LineAngleDifferenceDeg(double a_deg, double b_deg) {
  double d = std::abs(a_deg - b_deg);
  if (d >= 180.0) d = std::fmod(d, 180.0);
  return d > 90.0 ? 180.0 - d : d;
}

}  // namespace hairrig
