// A running sum of outer products a b^T whose total is symmetric (a = w b),
// kept as its lower triangle: all Eigen's SelfAdjointEigenSolver reads. Each
// entry is summed as a_i b_j (i >= j), in the order the terms are added, so
// the total's lower triangle equals that of summing the full Eigen products.
#pragma once

#include <Eigen/Core>

namespace hairrig {

struct SymmetricOuterSum {
  double xx = 0, yx = 0, zx = 0, yy = 0, zy = 0, zz = 0;

  void Add(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    xx += a.x() * b.x(), yx += a.y() * b.x(), zx += a.z() * b.x();
    yy += a.y() * b.y(), zy += a.z() * b.y(), zz += a.z() * b.z();
  }
  // The total, its upper triangle mirrored from the lower.
  Eigen::Matrix3d Matrix() const {
    Eigen::Matrix3d m;
    m << xx, yx, zx, yx, yy, zy, zx, zy, zz;
    return m;
  }
};

}  // namespace hairrig
