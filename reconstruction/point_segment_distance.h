// The distance between a point and a line segment, squared (units of the
// points; any frame). A segment of zero length is its end point.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace hairrig {

inline float PointSegmentDistance2(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                   const Eigen::Vector3f& b) {
  const Eigen::Vector3f ab = b - a;
  const float length2 = ab.squaredNorm();
  const float t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0f, 1.0f) : 0.0f;
  return (a + t * ab - p).squaredNorm();
}

}  // namespace hairrig
