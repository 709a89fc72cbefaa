// Whether a calibration's stated uncertainty can be trusted: the
// errors of solved views against the truth, compared with the errors their
// covariance predicts (calibration/bundle_adjustment.h, ViewUncertainty).
// A ratio of 1 means the stated uncertainty is right; above 1 it is
// optimistic, below 1 pessimistic. Radians, millimetres.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "calibration/bundle_adjustment.h"
#include "core/transform.h"

namespace hairrig {

struct UncertaintySample {
  Eigen::Vector3d rotation_error_rad =
      Eigen::Vector3d::Zero();                                // rotation vector, truth to estimate
  Eigen::Vector3d centre_error_mm = Eigen::Vector3d::Zero();  // camera centre in the box frame
  ViewUncertainty predicted;
};

// The errors of one view's cam_from_box; `predicted` as solved.
UncertaintySample MakeUncertaintySample(const Rigid3d& estimated_cam_from_box,
                                        const Rigid3d& true_cam_from_box,
                                        const ViewUncertainty& predicted);

struct UncertaintyRatios {
  int views = 0;  // samples with a finite covariance
  // sqrt(mean over views of |error|^2 / trace(covariance)): each view's error
  // over its predicted RMS error, pooled (one badly conditioned view cannot
  // dominate, as it would in a ratio of sums).
  double rotation = NAN, centre = NAN;
  // sqrt(mean(e' C^-1 e) / 3): the same, weighing each direction by its own uncertainty.
  double rotation_mahalanobis = NAN, centre_mahalanobis = NAN;
};

// Samples without a finite covariance are skipped; NaN ratios when none is left.
UncertaintyRatios ObservedOverPredicted(const std::vector<UncertaintySample>& samples);

}  // namespace hairrig
