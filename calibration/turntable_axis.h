// The turntable axis from the views themselves: as the
// turntable turns, each fixed camera's centre, seen from the box, traces a
// circle about the axis. A plane and circle fitted to those centres give the
// axis in the box frame, hence turntable_from_box, without a hand-set guess.
//
// Frames as in calibration/bundle_adjustment.h: the turntable turns by +theta
// about its z axis, so in the box frame a camera moves by -theta about it;
// that fixes the axis' sign. The axis' height (the origin along it) is not
// seen by the cameras and is taken from `height_mm` (the box origin's height
// in the turntable frame, from the rig config); so is its azimuth: the
// turntable's x axis is the box's x axis (projected across the axis) turned
// back by `yaw_deg`, the box's mounting turn about the axis.
#pragma once

#include <vector>

#include "calibration/bundle_adjustment.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

struct TurntableAxisFit {
  Rigid3d turntable_from_box;
  int camera = -1;           // the camera whose circle was used (most stops)
  double circle_rms_mm = 0;  // distance of its centres from the fitted circle
  double radius_mm = 0;
};

// FailedPrecondition if no camera has views at 3 or more distinct stops that
// span more than a few degrees.
Result<TurntableAxisFit> FitTurntableAxis(const std::vector<CalibrationView>& views,
                                          double height_mm, double yaw_deg = 0);

}  // namespace hairrig
