// The gradient of a scalar field by central differences of step h along
// each axis (the fields' voxel size), for the voxel fields of the strand
// stage (hybrid_field.h's distance field, interior_field.h's level set).
#pragma once

#include <Eigen/Core>

namespace hairrig {

// `field(p)` returns the field's value at p (double or float).
template <typename Field>
Eigen::Vector3f CentralGradient(const Field& field, const Eigen::Vector3f& p, float h) {
  Eigen::Vector3f gradient;
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Vector3f e = Eigen::Vector3f::Zero();
    e[axis] = h;
    gradient[axis] = static_cast<float>((field(p + e) - field(p - e)) / (2.0 * h));
  }
  return gradient;
}

}  // namespace hairrig
