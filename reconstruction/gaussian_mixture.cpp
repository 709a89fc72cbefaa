#include "reconstruction/gaussian_mixture.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

namespace hairrig {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

// Weighted mean and covariance (plus the floor) of the rows of `x` with
// weights `w` summing to `total` > 0.
void WeightedMoments(const Eigen::MatrixXd& x, const Eigen::VectorXd& w, double total, double floor,
                     MixtureComponent* c) {
  c->mean = (x.transpose() * w) / total;
  const Eigen::MatrixXd centred = x.rowwise() - c->mean.transpose();
  c->covariance = (centred.transpose() * w.asDiagonal() * centred) / total;
  c->covariance.diagonal().array() += floor;
}

void NormaliseWeights(GaussianMixture* m) {
  double total = 0;
  for (const MixtureComponent& c : m->components) total += c.weight;
  for (MixtureComponent& c : m->components) c.weight /= total;
}

// Components from k-means++ clusters: their members' moments and shares.
GaussianMixture Initialise(const cv::Mat1f& samples, const Eigen::MatrixXd& x,
                           const MixtureFitOptions& o) {
  // k-means draws from this thread's cv::theRNG(): seeded for the fit, then
  // given back as it was.
  const cv::RNG callers = cv::theRNG();
  cv::theRNG() = cv::RNG(o.seed);
  cv::Mat labels, centres;
  cv::kmeans(samples, o.components, labels, cv::TermCriteria(cv::TermCriteria::COUNT, 10, 0.5),
             o.kmeans_attempts, cv::KMEANS_PP_CENTERS, centres);
  cv::theRNG() = callers;
  const Eigen::Index n = x.rows();
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  GaussianMixture mixture;
  for (int k = 0; k < o.components; ++k) {
    Eigen::VectorXd member = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < n; ++i) member[i] = labels.at<int>(static_cast<int>(i)) == k;
    const double count = member.sum();
    MixtureComponent c;
    // An empty cluster starts as the whole sample's spread, with a token share.
    WeightedMoments(x, count > 0 ? member : ones, count > 0 ? count : double(n), o.variance_floor,
                    &c);
    c.weight = std::max(count, 1.0) / static_cast<double>(n);
    mixture.components.push_back(c);
  }
  NormaliseWeights(&mixture);
  return mixture;
}

// E-step: each sample's responsibilities (n x K) and the mean log-likelihood
// (NaN when a covariance is not positive definite).
double Responsibilities(const Eigen::MatrixXd& x, const GaussianMixture& m, Eigen::MatrixXd* resp) {
  const Eigen::Index n = x.rows(), dims = x.cols();
  const Eigen::Index k_count = static_cast<Eigen::Index>(m.components.size());
  resp->resize(n, k_count);
  for (Eigen::Index k = 0; k < k_count; ++k) {
    const MixtureComponent& c = m.components[static_cast<size_t>(k)];
    const Eigen::LLT<Eigen::MatrixXd> llt(c.covariance);
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    const Eigen::MatrixXd l = llt.matrixL();
    const double log_det = 2.0 * l.diagonal().array().log().sum();
    const double log_norm = std::log(std::max(c.weight, 1e-300)) -
                            0.5 * (static_cast<double>(dims) * kLog2Pi + log_det);
    const Eigen::MatrixXd centred = (x.rowwise() - c.mean.transpose()).transpose();
    const Eigen::MatrixXd z = l.triangularView<Eigen::Lower>().solve(centred);
    resp->col(k) = (log_norm - 0.5 * z.colwise().squaredNorm().array()).transpose();
  }
  double total = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double top = resp->row(i).maxCoeff();
    const double log_sum = top + std::log((resp->row(i).array() - top).exp().sum());
    resp->row(i) = (resp->row(i).array() - log_sum).exp();
    total += log_sum;
  }
  return total / static_cast<double>(n);
}

// M-step: weights, means and covariances from the responsibilities. A
// component that no sample supports keeps its parameters.
void Maximise(const Eigen::MatrixXd& x, const Eigen::MatrixXd& resp, double floor,
              GaussianMixture* m) {
  const double n = static_cast<double>(x.rows());
  for (Eigen::Index k = 0; k < resp.cols(); ++k) {
    MixtureComponent& c = m->components[static_cast<size_t>(k)];
    const double support = resp.col(k).sum();
    if (support < 1e-9) {
      c.weight = 1e-9;
      continue;
    }
    WeightedMoments(x, resp.col(k), support, floor, &c);
    c.weight = support / n;
  }
  NormaliseWeights(m);
}

}  // namespace

Status MixtureFitOptions::Check() const {
  if (components < 1 || components > 64) {
    return InvalidArgument("mixture components must be in 1..64, got " +
                           std::to_string(components));
  }
  if (max_iterations < 1) return InvalidArgument("mixture max_iterations must be at least 1");
  if (!(relative_tolerance >= 0) || !std::isfinite(relative_tolerance))
    return InvalidArgument("mixture relative_tolerance must be finite and >= 0");
  if (!(variance_floor > 0) || !std::isfinite(variance_floor))
    return InvalidArgument("mixture variance_floor must be finite and positive");
  if (kmeans_attempts < 1) return InvalidArgument("mixture kmeans_attempts must be at least 1");
  return Status::Ok();
}

Result<GaussianMixture> FitGaussianMixture(const cv::Mat1f& samples,
                                           const MixtureFitOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  if (samples.empty() || samples.cols > 8)
    return InvalidArgument("mixture samples need 1..8 feature columns and at least one row");
  if (samples.rows < 2 * options.components) {
    return FailedPrecondition("mixture of " + std::to_string(options.components) +
                              " components from only " + std::to_string(samples.rows) + " samples");
  }
  Eigen::MatrixXd x(samples.rows, samples.cols);
  for (int i = 0; i < samples.rows; ++i)
    for (int j = 0; j < samples.cols; ++j) x(i, j) = samples(i, j);
  if (!x.allFinite()) return FailedPrecondition("mixture samples contain NaN or infinity");

  GaussianMixture mixture = Initialise(samples, x, options);
  Eigen::MatrixXd resp;
  double previous = 0;
  // Each pass scores the current parameters (E-step), then stops once the
  // likelihood has settled or the M-steps are used up, else refits (M-step):
  // the reported likelihood is always the returned parameters'.
  for (int it = 0;; ++it) {
    const double likelihood = Responsibilities(x, mixture, &resp);
    if (!std::isfinite(likelihood)) {
      return FailedPrecondition(
          "the mixture's likelihood became non-finite (a covariance is not positive definite)");
    }
    mixture.mean_log_likelihood = likelihood;
    mixture.iterations = it;
    const bool settled = it > 0 && std::abs(likelihood - previous) <
                                       options.relative_tolerance * std::abs(likelihood);
    if (settled || it == options.max_iterations) break;
    previous = likelihood;
    Maximise(x, resp, options.variance_floor, &mixture);
  }
  return mixture;
}

}  // namespace hairrig
