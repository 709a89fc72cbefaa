#include "reconstruction/helix_fit.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "reconstruction/circle_fit.h"

namespace hairrig {

namespace {

constexpr double kChordMm = 3;
constexpr size_t kMinChords = 6;
constexpr double kMinSpreadRatio = 2;
constexpr double kMinTurnRad = M_PI / 2;
constexpr int kIterations = 30;

// The helix's parameters about a fixed reference frame (a0, u0, v0): the axis
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
// along the polyline.
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
    r[2 * i] = std::hypot(q.dot(u), q.dot(v)) - x[kRadius];
    r[2 * i + 1] = q.dot(a) - x[kSlope] * unwrapped - x[kOffset];
    if (angles != nullptr) angles->push_back(unwrapped);
  }
  return r;
}

// Levenberg-Marquardt with forward-difference derivatives; returns the
// parameters it ends on.
Parameters Refine(const std::vector<Eigen::Vector3d>& points, const Frame& frame, Parameters x) {
  double lambda = 1e-3;
  Eigen::VectorXd r = Residuals(points, frame, x, nullptr);
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    Eigen::MatrixXd jacobian(r.size(), 7);
    for (int k = 0; k < 7; ++k) {
      Parameters step = x;
      const double h = 1e-6 * std::max(1.0, std::abs(x[k]));
      step[k] += h;
      jacobian.col(k) = (Residuals(points, frame, step, nullptr) - r) / h;
    }
    const Eigen::Matrix<double, 7, 7> normal = jacobian.transpose() * jacobian;
    const Parameters gradient = jacobian.transpose() * r;
    bool improved = false;
    while (lambda < 1e8) {
      Eigen::Matrix<double, 7, 7> damped = normal;
      damped.diagonal() *= 1 + lambda;
      const Parameters candidate = x - damped.ldlt().solve(gradient);
      const Eigen::VectorXd candidate_r = Residuals(points, frame, candidate, nullptr);
      if (candidate.allFinite() && candidate_r.squaredNorm() < r.squaredNorm()) {
        improved = r.squaredNorm() - candidate_r.squaredNorm() > 1e-12 * r.squaredNorm();
        x = candidate;
        r = candidate_r;
        lambda = std::max(lambda / 10, 1e-9);
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return x;
}

}  // namespace

bool FitHelix(const std::vector<Eigen::Vector3f>& polyline, HelixShape* shape) {
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3f& p : polyline) points.push_back(p.cast<double>());
  std::vector<Eigen::Vector3d> chords;
  size_t j = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    j = std::max(j, k + 1);
    while (j < points.size() && (points[j] - points[k]).norm() < kChordMm) ++j;
    if (j == points.size()) break;
    chords.push_back((points[j] - points[k]).normalized());
  }
  if (chords.size() < kMinChords) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : chords) mean += c;
  mean /= static_cast<double>(chords.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& c : chords) covariance += (c - mean) * (c - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d spread = solver.eigenvalues();  // ascending
  if (!(spread(1) >= kMinSpreadRatio * spread(0))) return false;
  Frame frame;
  frame.a0 = solver.eigenvectors().col(0);
  if (frame.a0.dot(points.back() - points.front()) < 0) frame.a0 = -frame.a0;
  frame.u0 = solver.eigenvectors().col(1);
  frame.v0 = frame.a0.cross(frame.u0);
  std::vector<Eigen::Vector2d> across;
  for (const Eigen::Vector3d& p : points) across.emplace_back(p.dot(frame.u0), p.dot(frame.v0));
  Eigen::Vector2d centre;
  double radius = 0;
  if (!FitCircleTaubin(across, &centre, &radius) || !(radius < kMaxCircleRadiusMm)) return false;
  frame.centre0 = centre.x() * frame.u0 + centre.y() * frame.v0;
  // The height against the unwrapped angle, a line by least squares,
  // starts the slope and the offset (with both 0 the axial residual is the
  // height itself).
  Parameters x = Parameters::Zero();
  x[kRadius] = radius;
  std::vector<double> angles;
  const Eigen::VectorXd flat = Residuals(points, frame, x, &angles);
  Eigen::MatrixXd design(points.size(), 2);
  Eigen::VectorXd height(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    design.row(static_cast<Eigen::Index>(i)) << angles[i], 1;
    height[static_cast<Eigen::Index>(i)] = flat[static_cast<Eigen::Index>(2 * i + 1)];
  }
  const Eigen::Vector2d line = design.colPivHouseholderQr().solve(height);
  x[kSlope] = line[0];
  x[kOffset] = line[1];
  x = Refine(points, frame, x);
  Residuals(points, frame, x, &angles);
  if (!x.allFinite() || !(x[kRadius] > 0 && x[kRadius] < kMaxCircleRadiusMm) ||
      std::abs(angles.back() - angles.front()) < kMinTurnRad)
    return false;
  shape->radius_mm = x[kRadius];
  shape->pitch_mm = 2 * M_PI * std::abs(x[kSlope]);
  return true;
}

}  // namespace hairrig
