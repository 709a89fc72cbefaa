// A Gaussian mixture with full covariances fitted by expectation-maximisation
// (Dempster et al. 1977), started from k-means++ clusters: the colour (and
// texture) model of the hair segmentation (Bao & Qi 2017 Sec. III's GMM).
//
// The fit works on plain Eigen arrays, all samples at once per step.
// Features are in whatever units the caller uses (grey levels here).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct MixtureComponent {
  double weight = 0;           // share of the samples, sums to 1 over the components
  Eigen::VectorXd mean;        // dims
  Eigen::MatrixXd covariance;  // dims x dims, symmetric positive definite
};

struct GaussianMixture {
  std::vector<MixtureComponent> components;
  double mean_log_likelihood = 0;  // per sample, at the last iteration
  int iterations = 0;              // M-steps run
};

struct MixtureFitOptions {
  int components = 6;
  int max_iterations = 60;  // M-steps at most
  // Stop when the mean log-likelihood changes by less than this share of itself.
  double relative_tolerance = 1e-3;
  // Added to every covariance's diagonal at each M-step, so a component on a
  // constant feature stays invertible (feature units squared).
  double variance_floor = 1e-6;
  // k-means++ seeding draws from cv::RNG(seed) (the calling thread's
  // cv::theRNG() is restored afterwards): the same samples give the same fit.
  uint64_t seed = 0x5eed5eedULL;
  int kmeans_attempts = 10;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

// `samples`: one row per sample, one column per feature (1..8 columns).
// InvalidArgument for bad options or an empty or too wide sample matrix;
// FailedPrecondition when there are fewer samples than 2 per component, a
// sample is NaN or infinite, or a covariance stops being positive definite.
Result<GaussianMixture> FitGaussianMixture(const cv::Mat1f& samples,
                                           const MixtureFitOptions& options);

}  // namespace hairrig
