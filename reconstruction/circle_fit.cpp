#include "reconstruction/circle_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace hairrig {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// The sum of squared distances to the circle and, when `jtj` is given, the
// normal equations J'J and J'r of the residuals (height over the plane,
// in-plane distance to the rim; two per point) by (dc, da, db, dr), the
// normal moving as n + da e1 + db e2.
double SquaredDistances(const std::vector<Eigen::Vector3d>& points, const Circle3& circle,
                        const Eigen::Vector3d& e1, const Eigen::Vector3d& e2,
                        Matrix6d* jtj = nullptr, Vector6d* jtr = nullptr) {
  double sum = 0;
  if (jtj != nullptr) jtj->setZero(), jtr->setZero();
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d d = p - circle.center;
    const double height = d.dot(circle.normal);
    const Eigen::Vector3d in_plane = d - height * circle.normal;
    const double rho = in_plane.norm();
    const double rim = rho - circle.radius;
    sum += height * height + rim * rim;
    if (jtj == nullptr) continue;
    const Eigen::Vector3d radial = rho > 1e-12 ? Eigen::Vector3d(in_plane / rho) : e1;
    Vector6d height_row, rim_row;
    height_row << -circle.normal, d.dot(e1), d.dot(e2), 0.0;
    rim_row << -radial, -height * radial.dot(e1), -height * radial.dot(e2), -1.0;
    *jtj += height_row * height_row.transpose() + rim_row * rim_row.transpose();
    *jtr += height * height_row + rim * rim_row;
  }
  return sum;
}

// Levenberg-Marquardt on the centre, normal (two angles about the current
// one) and radius, minimising the squared geometric distances.
void RefineCircle(const std::vector<Eigen::Vector3d>& points, Circle3* circle) {
  constexpr int kIterations = 15;
  constexpr double kRelativeGain =
      1e-6;  // stop when a step gains less than this share of the cost (RMS 5e-7)
  double lambda = 1e-3;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    const Eigen::Vector3d e1 = circle->normal.unitOrthogonal(), e2 = circle->normal.cross(e1);
    Matrix6d jtj;
    Vector6d jtr;
    const double cost = SquaredDistances(points, *circle, e1, e2, &jtj, &jtr);
    if (cost <= 0) return;
    bool improved = false;
    for (int attempt = 0; attempt < 8 && !improved; ++attempt) {
      Matrix6d damped = jtj;
      damped.diagonal() += lambda * jtj.diagonal() + Vector6d::Constant(1e-12);
      const Vector6d step = damped.llt().solve(-jtr);
      Circle3 trial = *circle;
      trial.center += step.head<3>();
      trial.normal = (circle->normal + step(3) * e1 + step(4) * e2).normalized();
      trial.radius += step(5);
      const double trial_cost = SquaredDistances(points, trial, e1, e2);
      if (std::isfinite(trial_cost) && trial_cost < cost) {
        *circle = trial;
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = true;
        if (cost - trial_cost < kRelativeGain * cost) return;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) return;
  }
}

}  // namespace

double Circle3::Distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - center;
  const double height = d.dot(normal);
  const double rim = (d - height * normal).norm() - radius;
  return std::sqrt(height * height + rim * rim);
}

bool FitCircleTaubin(const std::vector<Eigen::Vector2d>& points, Eigen::Vector2d* center,
                     double* radius) {
  if (points.size() < 3) return false;
  const double count = static_cast<double>(points.size());
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) centroid += p;
  centroid /= count;
  double spread2 = 0;
  for (const Eigen::Vector2d& p : points) spread2 += (p - centroid).squaredNorm();
  const double scale = std::sqrt(spread2 / count);
  if (!(scale > 0)) return false;
  // In centred coordinates scaled to unit RMS spread, mean |q|^2 = 1. The
  // intercept that minimises the algebraic distances is c = -a mean |q|^2,
  // leaving v = (a, b): minimise v' S v, S the moments of (|q|^2 - 1, q),
  // subject to v' T v = 1, T = diag(4 mean |q|^2, 1, 1) (Taubin's
  // constraint); with u = T^(1/2) v, u is the smallest eigenvector of
  // T^(-1/2) S T^(-1/2).
  Eigen::Matrix3d moments = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q = (p - centroid) / scale;
    const Eigen::Vector3d v(q.squaredNorm() - 1.0, q.x(), q.y());
    moments += v * v.transpose();
  }
  moments /= count;
  const Eigen::Vector3d inv_sqrt_constraint(0.5, 1.0, 1.0);  // T^(-1/2), mean |q|^2 = 1
  const Eigen::Matrix3d reduced =
      inv_sqrt_constraint.asDiagonal() * moments * inv_sqrt_constraint.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(reduced);
  const Eigen::Vector3d v = inv_sqrt_constraint.cwiseProduct(eigen.eigenvectors().col(0));
  const double a = v(0);
  const Eigen::Vector2d b(v(1), v(2));
  // Centre -b / (2a), radius^2 = |b|^2 / (4 a^2) + 1 (scaled units).
  const double offset =
      std::abs(a) > 0 ? b.norm() / (2 * std::abs(a)) : std::numeric_limits<double>::infinity();
  if (offset * scale < kMaxCircleRadiusMm) {
    *center = centroid - scale * b / (2 * a);
    *radius = scale * std::sqrt(offset * offset + 1.0);
    return true;
  }
  // A straight line b.q = 0 (or a circle too large to tell from one).
  const Eigen::Vector2d away = (a < 0 ? 1.0 : -1.0) * b.normalized();
  *center = centroid + kMaxCircleRadiusMm * away;
  double sum = 0;
  for (const Eigen::Vector2d& p : points) sum += (p - *center).norm();
  *radius = sum / count;
  return true;
}

double FitCircle3(const std::vector<Eigen::Vector3d>& points, Circle3* circle) {
  if (points.size() < 3) return std::numeric_limits<double>::infinity();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  const Eigen::Vector3d normal = eigen.eigenvectors().col(0);  // the smallest spread's
  const Eigen::Vector3d u = eigen.eigenvectors().col(2), w = normal.cross(u);
  std::vector<Eigen::Vector2d> planar;
  planar.reserve(points.size());
  for (const Eigen::Vector3d& p : points)
    planar.emplace_back((p - centroid).dot(u), (p - centroid).dot(w));
  Eigen::Vector2d center2;
  double radius = 0;
  if (!FitCircleTaubin(planar, &center2, &radius)) return std::numeric_limits<double>::infinity();
  Circle3 fit;
  fit.center = centroid + center2.x() * u + center2.y() * w;
  fit.normal = normal;
  fit.radius = radius;
  RefineCircle(points, &fit);
  fit.radius = std::abs(fit.radius);
  if (fit.radius >
      kMaxCircleRadiusMm) {  // refined past straight: keep the centre's direction at the bound
    const Eigen::Vector3d away = (fit.center - centroid).normalized();
    fit.center = centroid + kMaxCircleRadiusMm * away;
    fit.radius = kMaxCircleRadiusMm;
  }
  *circle = fit;
  const Eigen::Vector3d e1 = fit.normal.unitOrthogonal(), e2 = fit.normal.cross(e1);
  return std::sqrt(SquaredDistances(points, fit, e1, e2) / static_cast<double>(points.size()));
}

double SweptArea(const std::vector<Eigen::Vector3d>& points, const Circle3& circle) {
  double area = 0;
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    area += (points[k] - circle.center).cross(points[k + 1] - circle.center).dot(circle.normal);
  }
  return area;
}

void OrientByTraversal(const std::vector<Eigen::Vector3d>& points, Circle3* circle) {
  if (SweptArea(points, *circle) < 0) circle->normal = -circle->normal;
}

double SweepOverlap(const std::vector<Eigen::Vector3d>& points, const Circle3& circle) {
  double signed_sweep = 0, unsigned_sweep = 0;
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    const double sweep =
        (points[k + 1] - circle.center).cross(points[k] - circle.center).dot(circle.normal);
    signed_sweep += sweep;
    unsigned_sweep += std::abs(sweep);
  }
  return unsigned_sweep > 0 ? 1.0 - std::abs(signed_sweep / unsigned_sweep) : 0.0;
}

}  // namespace hairrig
