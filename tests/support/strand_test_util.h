// Test helpers shared by the tests that read, write or fit strands.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/strands.h"

namespace hairrig {

// Same strands and bit-identical points.
inline void ExpectSameGeometry(const StrandSet& a, const StrandSet& b) {
  ASSERT_EQ(a.point_counts, b.point_counts);
  ASSERT_EQ(a.points_mm.size(), b.points_mm.size());
  for (size_t i = 0; i < a.points_mm.size(); ++i) {
    ASSERT_EQ(a.points_mm[i], b.points_mm[i]) << "point " << i;
  }
}

// Twelve curls (radius 5 mm, 40 points, 32 mm long, hanging down -z) on a
// 4 x 3 grid 20 mm apart: a small set to fit and simulate.
inline StrandSet TwelveCurls() {
  StrandSet set;
  for (int s = 0; s < 12; ++s) {
    std::vector<Eigen::Vector3f> p;
    for (int k = 0; k < 40; ++k) {
      const float a = 0.3f * static_cast<float>(k);
      p.emplace_back(20.0f * static_cast<float>(s % 4) + 5 * std::cos(a),
                     20.0f * static_cast<float>(s / 4) + 5 * std::sin(a),
                     -0.8f * static_cast<float>(k));
    }
    set.AddStrand(p);
  }
  return set;
}

}  // namespace hairrig
