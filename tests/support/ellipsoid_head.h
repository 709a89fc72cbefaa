// An ellipsoid head for strand tests: centre (0, 0, 250) mm, radii 80 x 80 x
// 100 mm (turntable frame), its scalp everything above 30 deg below the
// centre's level, with no parting.
#pragma once

#include "core/head_spec.h"

namespace hairrig_test {

inline hairrig::HeadSpec EllipsoidHeadWithWideScalp() {
  hairrig::HeadSpec spec;
  spec.center_turntable_mm = {0, 0, 250};
  spec.radii_mm = {80, 80, 100};
  spec.scalp.defined = true;
  spec.scalp.center_turntable_mm = spec.center_turntable_mm;
  spec.scalp.parting = false;
  spec.scalp.hairline_front_deg = spec.scalp.hairline_temple_deg = spec.scalp.hairline_ear_deg =
      -30;
  spec.scalp.hairline_nape_deg = -30;
  return spec;
}

}  // namespace hairrig_test
