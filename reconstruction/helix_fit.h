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
// On noisy arcs the radius comes out wide (4-27 % on the 20 mm synthetic
// arcs of helix_fit_test.cpp, 1-3 % on 40 mm ones; 20 % on a capture's seen
// arcs), the more so the noisier the points and the longer the pitch
// against the radius (there the axis' tilt and the radius are hard to tell
// apart).
// FitHelixLessItsBias measures that bias on each arc and takes it off.
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

// FitHelix less the fit's own bias at this arc's length, turn and noise (a
// parametric bootstrap's bias correction, Efron & Tibshirani, "An
// Introduction to the Bootstrap", 1993, Ch. 10): the fitted helix is
// sampled at the points' fitted angles, each sample moved by Gaussian noise
// of the points' noise per axis the residuals imply (the axial residual
// carries the noise along the circle times slope / radius, which is taken
// out), and fitted again, `resamples` times; the radius is then
// 2 r - median(r*) and the pitch 2 P - median(P*). The bias is measured at
// the fitted helix, not the true one: where it changes fast with the
// radius the correction overshoots (a stretched coil's short arcs, 4 / 30
// mm, come out 13 % narrow where the plain fit is 27 % wide,
// helix_fit_test.cpp). The noise model is the points' own, independent
// from point to point and the same along every axis: whatever the helix
// does not explain (a ringlet whose radius changes along it, a stereo error
// mostly in depth, smoothing along the strand) is read as noise and pushes
// towards over-correction. Points the helix passes through exactly (no
// residual) are returned as fitted. The noise is drawn from a fixed seed: one arc, one
// shape, with one build (the draws depend on the standard library). False
// (shape untouched) where FitHelix is, for resamples under 1, where fewer
// than half the resampled arcs can be fitted (the arc's noise hides its
// helix; curl_field.h then leaves the arc out, as it does those FitHelix
// refuses), and where the corrected radius or pitch is not positive. About
// resamples + 1 times FitHelix's cost.
bool FitHelixLessItsBias(const std::vector<Eigen::Vector3f>& points, HelixShape* shape,
                         int resamples = 16);

}  // namespace hairrig
