#include "reconstruction/helix_fit.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "core/statistics.h"
#include "reconstruction/circle_fit.h"

namespace hairrig {

namespace {

constexpr double kChordMm = 3;
constexpr size_t kMinChords = 6;
constexpr double kMinSpreadRatio = 2;
constexpr double kMinSpread = 1e-9;  // of the chords' unit directions' covariance
constexpr double kMinTurnRad = M_PI / 2;
constexpr int kIterations = 30;
constexpr double kMinRelativeGain = 1e-8;
// Seeds the resampled noise (with the arc's point count): the same arc, the same shape.
constexpr unsigned kResampleSeed = 20131;
constexpr double kNoNoiseMm = 1e-9;

// The helix's parameters about a fixed frame (a0, u0, v0, centre0): the axis
// a = normalise(a0 + tilt.x u0 + tilt.y v0) through centre0 + shift.x u0 +
// shift.y v0, the radius, the height per radian (signed: positive for a
// right-handed helix) and the height at angle 0.
using Parameters = Eigen::Matrix<double, 7, 1>;
enum { kTiltU, kTiltV, kShiftU, kShiftV, kRadius, kSlope, kOffset };

struct Frame {
  Eigen::Vector3d a0, u0, v0, centre0;
};

// The radial and axial residuals of every point (2 per point); `angles`
// (may be null) gets each point's angle about the axis (rad), unwrapped
// along the polyline from the first point's.
Eigen::VectorXd Residuals(const std::vector<Eigen::Vector3d>& points, const Frame& f,
                          const Parameters& x, std::vector<double>* angles) {
  const Eigen::Vector3d a = (f.a0 + x[kTiltU] * f.u0 + x[kTiltV] * f.v0).normalized();
  const Eigen::Vector3d u = (f.u0 - f.u0.dot(a) * a).normalized(), v = a.cross(u);
  const Eigen::Vector3d centre = f.centre0 + x[kShiftU] * f.u0 + x[kShiftV] * f.v0;
  Eigen::VectorXd r(2 * points.size());
  if (angles != nullptr) angles->clear();
  double previous = 0, unwrapped = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d q = points[i] - centre;
    const double angle = std::atan2(q.dot(v), q.dot(u));
    unwrapped = i == 0 ? angle : unwrapped + std::remainder(angle - previous, 2 * M_PI);
    previous = angle;
    const auto k = static_cast<Eigen::Index>(2 * i);
    r[k] = std::hypot(q.dot(u), q.dot(v)) - x[kRadius];
    r[k + 1] = q.dot(a) - x[kSlope] * unwrapped - x[kOffset];
    if (angles != nullptr) angles->push_back(unwrapped);
  }
  return r;
}

// d(residuals)/d(parameters): forward differences for the axis' tilt and
// shift, exact for the radius, slope and offset (the residuals are linear
// in them).
// `r` and `angles` are the residuals and angles at x.
Eigen::MatrixXd Jacobian(const std::vector<Eigen::Vector3d>& points, const Frame& frame,
                         const Parameters& x, const Eigen::VectorXd& r,
                         const std::vector<double>& angles) {
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(r.size(), 7);
  for (const int k : {kTiltU, kTiltV, kShiftU, kShiftV}) {
    // Tilts are radians-like, shifts mm: both near 0, the data within the
    // arc's own size of the frame's centre.
    constexpr double kStep = 1e-6;
    Parameters step = x;
    step[k] += kStep;
    jacobian.col(k) = (Residuals(points, frame, step, nullptr) - r) / kStep;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(2 * i);
    jacobian(row, kRadius) = -1;
    jacobian(row + 1, kSlope) = -angles[i];
    jacobian(row + 1, kOffset) = -1;
  }
  return jacobian;
}

// Levenberg-Marquardt from x; returns the parameters it ends on.
Parameters Refine(const std::vector<Eigen::Vector3d>& points, const Frame& frame, Parameters x) {
  double lambda = 1e-3;
  std::vector<double> angles, candidate_angles;
  Eigen::VectorXd r = Residuals(points, frame, x, &angles);
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    const Eigen::MatrixXd jacobian = Jacobian(points, frame, x, r, angles);
    const Eigen::Matrix<double, 7, 7> normal = jacobian.transpose() * jacobian;
    const Parameters gradient = jacobian.transpose() * r;
    double gain = 0;
    while (lambda < 1e8) {
      Eigen::Matrix<double, 7, 7> damped = normal;
      damped.diagonal() = damped.diagonal() * (1 + lambda) + Parameters::Constant(1e-12);
      const Parameters candidate = x - damped.ldlt().solve(gradient);
      const Eigen::VectorXd candidate_r = Residuals(points, frame, candidate, &candidate_angles);
      if (candidate.allFinite() && candidate_r.squaredNorm() < r.squaredNorm()) {
        gain = (r.squaredNorm() - candidate_r.squaredNorm()) / r.squaredNorm();
        x = candidate;
        r = candidate_r;
        angles.swap(candidate_angles);
        lambda = std::max(lambda / 10, 1e-9);
        break;
      }
      lambda *= 10;
    }
    if (gain < kMinRelativeGain) break;
  }
  return x;
}

// The unit directions of chords at least kChordMm long, one from each point
// that has one after it.
std::vector<Eigen::Vector3d> ChordDirections(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> chords;
  size_t j = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    j = std::max(j, k + 1);
    while (j < points.size() && (points[j] - points[k]).norm() < kChordMm) ++j;
    if (j == points.size()) break;
    chords.push_back((points[j] - points[k]).normalized());
  }
  return chords;
}

// The frame the refinement starts from: the axis a0 along which the chords
// vary least (pointing the way the polyline advances), the circle across it,
// u0 towards the first point (so its angle starts at 0, away from the cut at
// +-pi) and the centre level with the points' mean height (so a tilt pivots
// among them). Nothing when the chords do not spread round a cone or no
// finite circle fits.
std::optional<std::pair<Frame, double>> StartingFrame(const std::vector<Eigen::Vector3d>& points,
                                                      const std::vector<Eigen::Vector3d>& chords) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : chords) mean += c;
  mean /= static_cast<double>(chords.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& c : chords) covariance += (c - mean) * (c - mean).transpose();
  covariance /= static_cast<double>(chords.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d spread = solver.eigenvalues();  // ascending
  if (!(spread(1) > kMinSpreadRatio * spread(0) && spread(1) > kMinSpread)) return std::nullopt;
  Frame f;
  f.a0 = solver.eigenvectors().col(0);
  if (f.a0.dot(points.back() - points.front()) < 0) f.a0 = -f.a0;
  const Eigen::Vector3d e1 = solver.eigenvectors().col(1), e2 = f.a0.cross(e1);
  std::vector<Eigen::Vector2d> across;
  double height = 0;
  for (const Eigen::Vector3d& p : points) {
    across.emplace_back(p.dot(e1), p.dot(e2));
    height += p.dot(f.a0);
  }
  Eigen::Vector2d centre;
  double radius = 0;
  if (!FitCircleTaubin(across, &centre, &radius) || !(radius < kMaxCircleRadiusMm))
    return std::nullopt;
  f.centre0 =
      centre.x() * e1 + centre.y() * e2 + height / static_cast<double>(points.size()) * f.a0;
  const Eigen::Vector3d first = points.front() - f.centre0;
  f.u0 = (first - first.dot(f.a0) * f.a0).normalized();
  f.v0 = f.a0.cross(f.u0);
  if (!f.u0.allFinite()) return std::nullopt;
  return std::make_pair(f, radius);
}

// A fitted helix: its frame and parameters, each point's unwrapped angle
// about its axis (rad) and the points' noise per axis it implies (mm, the
// standard deviation of isotropic Gaussian noise).
struct FittedHelix {
  Frame frame;
  Parameters x;
  std::vector<double> angles;
  double sigma_mm = 0;
};

std::optional<FittedHelix> Fit(const std::vector<Eigen::Vector3d>& points) {
  const std::vector<Eigen::Vector3d> chords = ChordDirections(points);
  if (chords.size() < kMinChords) return std::nullopt;
  const auto start = StartingFrame(points, chords);
  if (!start) return std::nullopt;
  FittedHelix fit;
  fit.frame = start->first;
  // The height against the unwrapped angle, a line by least squares, starts
  // the slope and the offset (with both 0 the axial residual is the height).
  Parameters& x = fit.x;
  x = Parameters::Zero();
  x[kRadius] = start->second;
  const Eigen::VectorXd at_zero_slope = Residuals(points, fit.frame, x, &fit.angles);
  Eigen::MatrixXd design(points.size(), 2);
  Eigen::VectorXd heights(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    design.row(row) << fit.angles[i], 1;
    heights[row] = at_zero_slope[2 * row + 1];
  }
  const Eigen::Vector2d line = design.colPivHouseholderQr().solve(heights);
  x[kSlope] = line[0];
  x[kOffset] = line[1];
  x = Refine(points, fit.frame, x);
  const Eigen::VectorXd r = Residuals(points, fit.frame, x, &fit.angles);
  if (!x.allFinite() || !(x[kRadius] > 0 && x[kRadius] < kMaxCircleRadiusMm) ||
      std::abs(fit.angles.back() - fit.angles.front()) < kMinTurnRad)
    return std::nullopt;
  // A point's noise along the circle moves its angle, and with the angle its
  // expected height: its axial residual carries the noise along the circle
  // times slope / radius beside the noise along the axis.
  const double inflation = 1 + (x[kSlope] / x[kRadius]) * (x[kSlope] / x[kRadius]);
  double sum = 0;
  for (Eigen::Index k = 0; k < r.size(); k += 2)
    sum += r[k] * r[k] + r[k + 1] * r[k + 1] / inflation;
  fit.sigma_mm = std::sqrt(sum / std::max(1.0, static_cast<double>(r.size()) - 7));
  return fit;
}

HelixShape ShapeOf(const Parameters& x) { return {x[kRadius], 2 * M_PI * std::abs(x[kSlope])}; }

// The fitted helix's points at the fitted angles, each moved by Gaussian
// noise of sigma_mm per axis.
std::vector<Eigen::Vector3d> Resample(const FittedHelix& fit, double sigma_mm,
                                      std::mt19937* random) {
  const Frame& f = fit.frame;
  const Parameters& x = fit.x;
  const Eigen::Vector3d a = (f.a0 + x[kTiltU] * f.u0 + x[kTiltV] * f.v0).normalized();
  const Eigen::Vector3d u = (f.u0 - f.u0.dot(a) * a).normalized(), v = a.cross(u);
  const Eigen::Vector3d centre = f.centre0 + x[kShiftU] * f.u0 + x[kShiftV] * f.v0;
  std::normal_distribution<double> noise(0.0, sigma_mm);
  std::vector<Eigen::Vector3d> points;
  points.reserve(fit.angles.size());
  for (const double angle : fit.angles) {
    const Eigen::Vector3d on_helix = centre +
                                     x[kRadius] * (std::cos(angle) * u + std::sin(angle) * v) +
                                     (x[kSlope] * angle + x[kOffset]) * a;
    // Drawn in a fixed order (a constructor's arguments are evaluated in
    // an unspecified one).
    const double dz = noise(*random), dy = noise(*random), dx = noise(*random);
    points.push_back(on_helix + Eigen::Vector3d(dx, dy, dz));
  }
  return points;
}

std::vector<Eigen::Vector3d> ToDouble(const std::vector<Eigen::Vector3f>& polyline) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(polyline.size());
  for (const Eigen::Vector3f& p : polyline) points.push_back(p.cast<double>());
  return points;
}

}  // namespace

bool FitHelix(const std::vector<Eigen::Vector3f>& polyline, HelixShape* shape) {
  const std::optional<FittedHelix> fit = Fit(ToDouble(polyline));
  if (!fit) return false;
  *shape = ShapeOf(fit->x);
  return true;
}

bool FitHelixLessItsBias(const std::vector<Eigen::Vector3f>& polyline, HelixShape* shape,
                         int resamples) {
  const std::optional<FittedHelix> fit = Fit(ToDouble(polyline));
  if (!fit || resamples < 1) return false;
  const HelixShape fitted = ShapeOf(fit->x);
  // No residual: no noise to resample, no bias.
  if (!(fit->sigma_mm > kNoNoiseMm)) {
    *shape = fitted;
    return true;
  }
  std::mt19937 random(kResampleSeed + static_cast<unsigned>(polyline.size()));
  std::vector<double> radii, pitches;
  for (int k = 0; k < resamples; ++k) {
    const std::optional<FittedHelix> refit = Fit(Resample(*fit, fit->sigma_mm, &random));
    if (!refit) continue;
    radii.push_back(refit->x[kRadius]);
    pitches.push_back(ShapeOf(refit->x).pitch_mm);
  }
  if (2 * radii.size() < static_cast<size_t>(resamples)) return false;
  const HelixShape less_bias{2 * fitted.radius_mm - Median(radii),
                             2 * fitted.pitch_mm - Median(pitches)};
  if (!(less_bias.radius_mm > 0 && less_bias.pitch_mm > 0)) return false;
  *shape = less_bias;
  return true;
}

}  // namespace hairrig
