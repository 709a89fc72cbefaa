#include "reconstruction/point_orientation_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "reconstruction/symmetric_outer_sum.h"

namespace hairrig {
namespace {

std::vector<Eigen::Vector3f> Positions(const std::vector<OrientedPoint>& points) {
  std::vector<Eigen::Vector3f> positions(points.size());
  for (size_t i = 0; i < points.size(); ++i) positions[i] = points[i].position_mm;
  return positions;
}

}  // namespace

PointOrientationField::PointOrientationField(const std::vector<OrientedPoint>& points,
                                             double sigma_mm)
    : points_(points),
      positions_(Positions(points)),
      sigma_mm_(sigma_mm),
      grid_(positions_, 2 * sigma_mm) {
  slot_direction_.reserve(points.size());
  slot_weight_.reserve(points.size());
  for (const uint32_t i : grid_.order()) {
    slot_direction_.push_back(points[i].direction);
    slot_weight_.push_back(std::max(points[i].confidence, 1e-3f));
  }
}

bool PointOrientationField::At(const Eigen::Vector3f& p, const Eigen::Vector3f& reference,
                               double min_abs_cos, int min_neighbours, Eigen::Vector3f* orientation,
                               int* neighbours) const {
  const bool filter = reference.squaredNorm() > 0;
  const double inv_two_sigma2 = 1.0 / (2 * sigma_mm_ * sigma_mm_);
  SymmetricOuterSum tensor;
  int count = 0;
  grid_.ForEachSlotWithin(p, 2 * sigma_mm_, [&](uint32_t slot, double d2) {
    const Eigen::Vector3f& o = slot_direction_[slot];
    if (filter && std::abs(o.dot(reference)) <= min_abs_cos) return;
    const double w = std::exp(-d2 * inv_two_sigma2) * slot_weight_[slot];
    const Eigen::Vector3d od = o.cast<double>();
    tensor.Add(w * od, od);
    ++count;
  });
  if (neighbours != nullptr) *neighbours = count;
  if (count < min_neighbours || count == 0) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(tensor.Matrix());
  Eigen::Vector3f o = eigen.eigenvectors().col(2).cast<float>();  // the largest eigenvalue's
  if (filter && o.dot(reference) < 0) o = -o;
  *orientation = o.normalized();
  return true;
}

std::vector<OrientedPoint> SmoothDirections(std::vector<OrientedPoint> points, double sigma_mm,
                                            double min_abs_cos, int threads) {
  // The new directions first, then written into the points the field has
  // stopped reading (no copy of the points and their view lists).
  std::vector<Eigen::Vector3f> directions(points.size());
  {
    const PointOrientationField field(points, sigma_mm);
    ParallelFor(points.size(), threads, [&] {
      return [&](size_t i) {
        directions[i] = points[i].direction;
        field.At(points[i].position_mm, points[i].direction, min_abs_cos, 1, &directions[i]);
      };
    });
  }
  for (size_t i = 0; i < points.size(); ++i) points[i].direction = directions[i];
  return points;
}

}  // namespace hairrig
