// Whether the views agree with a camera's intrinsics prior (a ChArUco
// calibration passed with `calibrate --intrinsics`). The views are solved a
// second time with free intrinsics (k3 held at the prior's value); the
// difference d between those intrinsics and the prior is tested against the
// two estimates' summed covariance C = C_views + diag(prior standard
// deviations^2):
//
//   chi2 = d' C^+ d   over the rank of C (the parameters the views estimate)
//
// With a prior of the camera itself, chi2 follows the chi-square distribution;
// a prior of another camera (a file relabelled, or the cameras' files swapped)
// drives it far above. The chi-square is stated as the one-sided normal
// deviate of the same tail probability (Wilson-Hilferty), so one threshold in
// sigma serves any number of parameters. Pixels for fx, fy, cx, cy; the
// distortion coefficients are unitless.
#pragma once

#include <array>
#include <string>

#include "calibration/bundle_adjustment.h"
#include "core/camera_model.h"

namespace hairrig {

struct PriorCheckOptions {
  // The prior is rejected when the chi-square's normal deviate exceeds this
  // (5 sigma: a tail probability of 3e-7 for a prior of the camera itself).
  double reject_sigma = 5.0;

  // InvalidArgument naming reject_sigma unless it is finite and positive.
  Status Check() const;
};

struct PriorCheck {
  bool tested = false;
  std::string not_tested;  // why not, when !tested (the views' covariance is unknown)
  CameraIntrinsics prior;
  CameraIntrinsics from_views;  // the intrinsics the views alone support
  std::array<double, CameraIntrinsics::kNumParams> from_views_stddev{};
  double chi2 = 0;
  int dof = 0;       // parameters compared (the rank of C)
  double sigma = 0;  // chi2 as a one-sided normal deviate
  // The parameter whose difference is the most standard deviations
  // (sqrt(C_ii)) from zero, and that many.
  int worst_param = -1;
  double worst_param_sigma = 0;
  bool rejected = false;
};

// `from_views_covariance` as BundleAdjustmentResult::intrinsics_covariance
// (NaN: not tested); `prior_stddev` as CalibrationCamera::nominal_stddev (all
// 0: the prior's own uncertainty is not known and only the views' counts).
// Bad options (PriorCheckOptions::Check) leave the prior not tested, with
// the reason in `not_tested`.
PriorCheck CheckIntrinsicsPrior(
    const CameraIntrinsics& prior,
    const std::array<double, CameraIntrinsics::kNumParams>& prior_stddev,
    const CameraIntrinsics& from_views, const IntrinsicsCovariance& from_views_covariance,
    const PriorCheckOptions& options = {});

// The one-sided standard normal deviate with the upper tail probability of
// `chi2` under a chi-square distribution with `dof` degrees of freedom, by
// the Wilson-Hilferty transform. It gives 4.8-4.9 where the exact deviate
// is 5 (3 to 8 degrees of freedom) and falls further below it beyond (8.1
// for an exact 8.6 at 8), so that a rejection by it is conservative.
double ChiSquareSigma(double chi2, int dof);

// One line for a technician: which parameter disagrees and by how much,
// e.g. "fx_px 1750.0 (prior) vs 1760.1 px (views), 9.8 sigma; chi-square 142
// over 8 parameters (10.2 sigma)".
std::string DescribePriorCheck(const PriorCheck& check);

}  // namespace hairrig
