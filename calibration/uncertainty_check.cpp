#include "calibration/uncertainty_check.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>

namespace hairrig {

UncertaintySample MakeUncertaintySample(const Rigid3d& estimated_cam_from_box,
                                        const Rigid3d& true_cam_from_box,
                                        const ViewUncertainty& predicted) {
  UncertaintySample s;
  // Same convention as ViewUncertainty::rotation_cov_rad2: estimate = Exp(e) * truth.
  const Eigen::AngleAxisd d(estimated_cam_from_box.rotation *
                            true_cam_from_box.rotation.conjugate());
  s.rotation_error_rad = d.angle() * d.axis();
  s.centre_error_mm =
      estimated_cam_from_box.Inverse().translation - true_cam_from_box.Inverse().translation;
  s.predicted = predicted;
  return s;
}

UncertaintyRatios ObservedOverPredicted(const std::vector<UncertaintySample>& samples) {
  double rot_sq = 0, centre_sq = 0, rot_mahal = 0, centre_mahal = 0;
  UncertaintyRatios r;
  for (const UncertaintySample& s : samples) {
    const Eigen::Matrix3d& c_rot = s.predicted.rotation_cov_rad2;
    const Eigen::Matrix3d& c_centre = s.predicted.centre_cov_mm2;
    if (!c_rot.allFinite() || !c_centre.allFinite() || !(c_rot.trace() > 0) ||
        !(c_centre.trace() > 0))
      continue;
    rot_sq += s.rotation_error_rad.squaredNorm() / c_rot.trace();
    centre_sq += s.centre_error_mm.squaredNorm() / c_centre.trace();
    rot_mahal += s.rotation_error_rad.dot(c_rot.ldlt().solve(s.rotation_error_rad));
    centre_mahal += s.centre_error_mm.dot(c_centre.ldlt().solve(s.centre_error_mm));
    ++r.views;
  }
  if (r.views == 0) return r;
  r.rotation = std::sqrt(rot_sq / r.views);
  r.centre = std::sqrt(centre_sq / r.views);
  r.rotation_mahalanobis = std::sqrt(rot_mahal / (3.0 * r.views));
  r.centre_mahalanobis = std::sqrt(centre_mahal / (3.0 * r.views));
  return r;
}

}  // namespace hairrig
