// Test helper shared by the strand-format tests.
#pragma once

#include <gtest/gtest.h>

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

}  // namespace hairrig
