#include "calibration/prior_check.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <vector>

namespace hairrig {

namespace {

// Eigenvalues of the normalised covariance below this fraction of the largest
// are a direction the two estimates do not constrain: left out of chi2.
constexpr double kRankTolerance = 1e-9;

struct Mahalanobis {
  double chi2 = 0;
  int dof = 0;
};

// d' C^+ d for a covariance whose diagonal is 1 (a correlation matrix).
Mahalanobis PseudoInverseDistance(const Eigen::MatrixXd& correlation, const Eigen::VectorXd& d) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(correlation);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const Eigen::VectorXd projected = eigen.eigenvectors().transpose() * d;
  Mahalanobis out;
  for (Eigen::Index k = 0; k < values.size(); ++k) {
    if (!(values(k) > kRankTolerance * values.maxCoeff())) continue;
    out.chi2 += projected(k) * projected(k) / values(k);
    ++out.dof;
  }
  return out;
}

std::string Format(const char* format, double a, double b = 0, double c = 0) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, format, a, b, c);
  return buffer;
}

}  // namespace

Status PriorCheckOptions::Check() const {
  if (!(reject_sigma > 0) || !std::isfinite(reject_sigma))
    return InvalidArgument("reject_sigma must be a finite positive number of sigmas");
  return Status::Ok();
}

double ChiSquareSigma(double chi2, int dof) {
  if (dof <= 0) return 0;
  const double k = dof;
  const double spread = std::sqrt(2.0 / (9.0 * k));
  return (std::cbrt(std::max(0.0, chi2) / k) - (1.0 - 2.0 / (9.0 * k))) / spread;
}

PriorCheck CheckIntrinsicsPrior(
    const CameraIntrinsics& prior,
    const std::array<double, CameraIntrinsics::kNumParams>& prior_stddev,
    const CameraIntrinsics& from_views, const IntrinsicsCovariance& from_views_covariance,
    const PriorCheckOptions& options) {
  PriorCheck out;
  out.prior = prior;
  out.from_views = from_views;
  if (const Status valid = options.Check(); !valid.ok()) {
    out.not_tested = "prior check options: " + valid.message();
    return out;
  }
  if (!from_views_covariance.allFinite()) {
    out.not_tested = "the covariance of the intrinsics the views alone give cannot be computed";
    return out;
  }
  const auto p = prior.ToParams(), v = from_views.ToParams();
  std::vector<int> compared;  // the parameters the views estimate
  for (int i = 0; i < CameraIntrinsics::kNumParams; ++i) {
    out.from_views_stddev[static_cast<size_t>(i)] =
        std::sqrt(std::max(0.0, from_views_covariance(i, i)));
    if (from_views_covariance(i, i) > 0) compared.push_back(i);
  }
  if (compared.empty()) {
    out.not_tested = "the views alone estimate none of the intrinsics";
    return out;
  }
  // Normalised by each parameter's summed standard deviation, so that the
  // pixels and the distortion coefficients meet on one scale.
  const auto prior_variance = [&](int i, int j) {
    return i == j ? prior_stddev[static_cast<size_t>(i)] * prior_stddev[static_cast<size_t>(i)]
                  : 0.0;
  };
  const Eigen::Index n = static_cast<Eigen::Index>(compared.size());
  Eigen::VectorXd d(n), sd(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const int i = compared[static_cast<size_t>(a)];
    sd(a) = std::sqrt(from_views_covariance(i, i) + prior_variance(i, i));
    d(a) = (v[static_cast<size_t>(i)] - p[static_cast<size_t>(i)]) / sd(a);
    if (std::abs(d(a)) > out.worst_param_sigma) {
      out.worst_param_sigma = std::abs(d(a));
      out.worst_param = i;
    }
  }
  Eigen::MatrixXd correlation(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) {
      const int i = compared[static_cast<size_t>(a)], j = compared[static_cast<size_t>(b)];
      correlation(a, b) = (from_views_covariance(i, j) + prior_variance(i, j)) / (sd(a) * sd(b));
    }
  }
  const Mahalanobis distance = PseudoInverseDistance(correlation, d);
  out.tested = true;
  out.chi2 = distance.chi2;
  out.dof = distance.dof;
  out.sigma = ChiSquareSigma(out.chi2, out.dof);
  out.rejected = out.sigma > options.reject_sigma;
  return out;
}

std::string DescribePriorCheck(const PriorCheck& check) {
  if (!check.tested) return "not tested: " + check.not_tested;
  std::string text;
  if (check.worst_param >= 0) {
    const size_t i = static_cast<size_t>(check.worst_param);
    const bool pixels = i < 4;
    text = std::string(CameraIntrinsics::kParamNames[i]) +
           Format(pixels ? " %.1f (prior) vs %.1f (views) px" : " %.5g (prior) vs %.5g (views)",
                  check.prior.ToParams()[i], check.from_views.ToParams()[i]) +
           Format(", %.1f sigma; ", check.worst_param_sigma);
  }
  return text + Format("chi-square %.1f over %.0f parameters, %.1f sigma", check.chi2, check.dof,
                       check.sigma);
}

}  // namespace hairrig
