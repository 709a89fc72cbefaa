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
//      direction along which the 3 mm chords' directions vary least (the
//      least eigenvector of their covariance).
//   2. The circle the points trace seen along that axis (Taubin's fit,
//      circle_fit.h) gives the centre and the radius; the height along the
//      axis against the unwrapped angle about the centre, a straight line,
//      gives the pitch (its slope times 2 pi).
//   3. Gauss-Newton (Levenberg-Marquardt damped) on the axis' direction, its
//      position, the radius, the slope and the height's offset together,
//      minimising each point's radial and axial residual to the helix: the
//      axis from step 1 tilts with the chords' noise, and a circle fitted
//      across a tilted axis is an ellipse's, too small.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hairrig {

struct HelixShape {
  double radius_mm = 0, pitch_mm = 0;
};

// False (shape untouched) for fewer than 6 chords of 3 mm, chords that do not
// spread round a cone (their middle spread under 4 times the least: an arc
// that barely turns, whose axis no direction fixes), an arc that turns less
// than a quarter turn about the fitted axis, or no finite circle.
bool FitHelix(const std::vector<Eigen::Vector3f>& points, HelixShape* shape);

}  // namespace hairrig
