// The helix a polyline winds on (a seen arc of a ringlet), fitted to its
// points. Units mm, any frame.
//
// The fit uses positions and first differences only. The per-step curvature
// and torsion of a polyline (second and third differences) grow with its
// points' noise, torsion most: on a path tracer's curls the torsion comes out
// about twice the true helix's and the radius r = kappa / (kappa^2 + tau^2)
// under two thirds of it (docs/accuracy.md, "The curl's shape from the arcs'
// own helices").
//   1. The axis: a helix's chords of one length all make one angle with its
//      axis, so their directions lie on a cone about it; the axis is the
//      direction along which the directions of the chords from each point to
//      the first point at least 3 mm on vary least (the least eigenvector of
//      their covariance). On points about 1 mm apart the chords are 3-4 mm
//      long, which changes their angle to the axis by under 1 %.
//   2. The circle the points trace seen along that axis (Taubin's fit,
//      circle_fit.h) gives the centre and the radius; the height along the
//      axis against the unwrapped angle about the centre, a straight line,
//      gives the slope (height per radian).
//   3. Levenberg-Marquardt on the axis' direction, its position, the radius,
//      the slope and the height's offset together, minimising each point's
//      radial and axial residual to the helix: the axis from step 1 tilts
//      with the chords' noise, and a circle fitted across a tilted axis is
//      an ellipse's, too small (3.9 mm against 6 on the path tracer's curls,
//      docs/accuracy.md).
// On noisy arcs the radius comes out a few per cent wide (3-8 % on the
// synthetic arcs of helix_fit_test.cpp; 20 % on a capture's seen arcs).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hairrig {

struct HelixShape {
  double radius_mm = 0, pitch_mm = 0;
};

// The pitch is unsigned (the handedness is not fitted). False (shape
// untouched) for fewer than 6 chords, chords that do not spread round a cone
// (their middle spread at most twice the least: an arc that barely turns,
// whose axis no direction fixes), an arc that turns less than a quarter turn
// about the fitted axis (on a helix of radius r and pitch P, an arc shorter
// than (pi / 2) hypot(r, P / 2 pi): 11 mm for 6 / 20 mm, 32 mm for 20 / 20),
// no finite circle, or points that are not finite.
bool FitHelix(const std::vector<Eigen::Vector3f>& points, HelixShape* shape);

}  // namespace hairrig
