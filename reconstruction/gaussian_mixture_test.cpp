#include "reconstruction/gaussian_mixture.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <thread>

namespace hairrig {
namespace {

// `count` samples of a 3D Gaussian with the given mean and per-axis sigma,
// rotated about z by `angle` (rad), appended to `rows`.
void AddCluster(const Eigen::Vector3d& mean, const Eigen::Vector3d& sigma, double angle, int count,
                std::mt19937* rng, std::vector<Eigen::Vector3d>* rows) {
  std::normal_distribution<double> unit(0.0, 1.0);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d z(unit(*rng), unit(*rng), unit(*rng));
    rows->push_back(mean + r * sigma.cwiseProduct(z));
  }
}

cv::Mat1f ToMat(const std::vector<Eigen::Vector3d>& rows, int dims) {
  cv::Mat1f m(static_cast<int>(rows.size()), dims, 0.0f);
  for (size_t i = 0; i < rows.size(); ++i)
    for (int j = 0; j < std::min(dims, 3); ++j) m(static_cast<int>(i), j) = float(rows[i][j]);
  return m;
}

// The component whose mean is nearest `mean`.
const MixtureComponent& Nearest(const GaussianMixture& m, const Eigen::Vector3d& mean) {
  return *std::min_element(m.components.begin(), m.components.end(),
                           [&](const MixtureComponent& a, const MixtureComponent& b) {
                             return (a.mean.head<3>() - mean).norm() <
                                    (b.mean.head<3>() - mean).norm();
                           });
}

TEST(GaussianMixture, RecoversThreeClustersWeightsMeansAndCovariances) {
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3d> rows;
  const Eigen::Vector3d a(40, 60, 80), b(120, 100, 90), c(200, 180, 150);
  AddCluster(a, {8, 3, 4}, 0.6, 3000, &rng, &rows);  // elongated, rotated: full covariance
  AddCluster(b, {5, 5, 5}, 0.0, 2000, &rng, &rows);
  AddCluster(c, {2, 6, 3}, -0.3, 1000, &rng, &rows);
  std::shuffle(rows.begin(), rows.end(), rng);
  MixtureFitOptions options;
  options.components = 3;
  const Result<GaussianMixture> fit = FitGaussianMixture(ToMat(rows, 3), options);
  ASSERT_TRUE(fit.ok()) << fit.status().ToString();
  ASSERT_EQ(fit->components.size(), 3u);
  const double weights[3] = {0.5, 1.0 / 3, 1.0 / 6};
  const Eigen::Vector3d means[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const MixtureComponent& found = Nearest(*fit, means[k]);
    EXPECT_NEAR(found.weight, weights[k], 0.01) << k;
    EXPECT_LT((found.mean - means[k]).norm(), 0.6) << k;
  }
  // The elongated cluster's covariance: its largest variance 8^2 along 0.6 rad.
  const MixtureComponent& first = Nearest(*fit, a);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(first.covariance);
  EXPECT_NEAR(std::sqrt(eig.eigenvalues()[2]), 8.0, 0.4);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);
  EXPECT_GT(std::abs(axis.dot(Eigen::Vector3d(std::cos(0.6), std::sin(0.6), 0))), 0.99);
  EXPECT_LT(fit->iterations, options.max_iterations) << "it settles before the cap";
  double weights_sum = 0;
  for (const MixtureComponent& component : fit->components) weights_sum += component.weight;
  EXPECT_NEAR(weights_sum, 1.0, 1e-12);
  // Well separated, each sample's log-likelihood is its own cluster's log
  // weight plus log-density: -1.5 log(2 pi) - 1.5 - log(sx sy sz) on average,
  // -9.51, -10.18 and -9.63 for the three, -9.76 weighted.
  EXPECT_NEAR(fit->mean_log_likelihood, -9.76, 0.1);
}

TEST(GaussianMixture, AConstantFeatureStaysInvertibleAndTheFitRepeats) {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector3d> rows;
  AddCluster({10, 10, 10}, {1, 1, 1}, 0.0, 500, &rng, &rows);
  AddCluster({30, 10, 10}, {1, 1, 1}, 0.0, 500, &rng, &rows);
  const cv::Mat1f samples = ToMat(rows, 4);  // the fourth column is 0 everywhere
  MixtureFitOptions options;
  options.components = 2;
  const Result<GaussianMixture> first = FitGaussianMixture(samples, options);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  // Another thread, whose OpenCV generator has drawn before: the same fit.
  cv::theRNG().next();
  Result<GaussianMixture> second = InvalidArgument("not run");
  std::thread other([&] {
    cv::theRNG() = cv::RNG(12345);
    second = FitGaussianMixture(samples, options);
  });
  other.join();
  ASSERT_TRUE(second.ok());
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_TRUE(first->components[k].covariance.allFinite());
    EXPECT_NEAR(first->components[k].covariance(3, 3), options.variance_floor, 1e-12);
    EXPECT_EQ(first->components[k].mean, second->components[k].mean) << "same seed, same fit";
  }
  // The caller's generator is given back as it was.
  const cv::RNG before = cv::theRNG();
  ASSERT_TRUE(FitGaussianMixture(samples, options).ok());
  EXPECT_EQ(cv::theRNG().state, before.state);
}

// Four distinct colours in 400 samples and six components: clusters are
// left empty or collapse onto one colour; the fit still ends with finite
// parameters whose weights sum to 1.
TEST(GaussianMixture, FewerDistinctSamplesThanComponentsStillFit) {
  cv::Mat1f samples(400, 3);
  for (int i = 0; i < samples.rows; ++i)
    for (int j = 0; j < 3; ++j) samples(i, j) = static_cast<float>(40 * (i % 4) + 10 * j);
  MixtureFitOptions options;
  options.components = 6;
  const Result<GaussianMixture> fit = FitGaussianMixture(samples, options);
  ASSERT_TRUE(fit.ok()) << fit.status().ToString();
  double weights_sum = 0;
  for (const MixtureComponent& c : fit->components) {
    EXPECT_TRUE(c.mean.allFinite() && c.covariance.allFinite());
    weights_sum += c.weight;
  }
  EXPECT_NEAR(weights_sum, 1.0, 1e-12);
  EXPECT_TRUE(std::isfinite(fit->mean_log_likelihood));
}

TEST(GaussianMixture, RefusesTooFewSamplesNaNsAndBadOptions) {
  MixtureFitOptions options;
  options.components = 4;
  cv::Mat1f few(7, 3, 1.0f);
  const Result<GaussianMixture> too_few = FitGaussianMixture(few, options);
  ASSERT_FALSE(too_few.ok());
  EXPECT_NE(too_few.status().message().find("only 7 samples"), std::string::npos);

  cv::Mat1f with_nan(100, 3, 1.0f);
  with_nan(50, 1) = std::nanf("");
  EXPECT_FALSE(FitGaussianMixture(with_nan, options).ok());

  options.components = 0;
  const Result<GaussianMixture> bad = FitGaussianMixture(cv::Mat1f(100, 3, 1.0f), options);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("components"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
