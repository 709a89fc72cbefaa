// The capture plan and its policies, read from the rig config's `plan`,
// `retries` and `storage` sections (etc/sim-rig.yaml documents every field).
//
// A plan is a list of views; a view is one camera's frame at one turntable
// stop under one light state. Views that share the stop's angle and light
// state are shot together, on one trigger. The default plan is 19 evenly
// spaced stops x every camera = 38 views, numbered view = stop * cameras +
// camera, the numbering the simulated rig's ground truth uses.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "drivers/camera.h"
#include "drivers/registry.h"
#include "drivers/turntable.h"

namespace hairrig {

struct PlannedView {
  int index = 0;  // 0-based; names the frame files
  int stop = 0;   // index into CapturePlan::stops
  std::string camera_name;
  std::string camera_serial;
};

struct PlannedStop {
  int index = 0;
  double angle_deg = 0;
  std::map<std::string, double> light_levels;  // light name -> 0..1
  std::vector<int> views;                      // indices into CapturePlan::views
};

struct CapturePlan {
  std::vector<PlannedView> views;
  std::vector<PlannedStop> stops;
  MotionProfile motion;
  bool home_first = true;
  CaptureSettings camera_settings;  // exposure, gain and format for every camera
  // Width of each pulse on a trigger line (plan field trigger_pulse_us): long
  // enough for the slowest input on the line (opto-isolated camera inputs
  // want tens of microseconds; a DSLR's wired remote, tens of milliseconds).
  std::chrono::microseconds trigger_pulse{100};
};

// Attempts with exponential back-off: try, wait backoff_s, try, wait
// backoff_s * factor, ... up to `attempts` tries in all.
struct RetryPolicy {
  int attempts = 3;
  double backoff_s = 0.2;  // wall-clock seconds
  double backoff_factor = 2.0;
  double BackoffBefore(int attempt) const;  // attempt 2, 3, ...; 0 for the first
};

struct CapturePolicies {
  RetryPolicy camera{3, 0.2, 2.0};     // reopen a camera, re-shoot a view
  RetryPolicy turntable{2, 0.5, 2.0};  // re-command a move that timed out
  RetryPolicy light{3, 0.1, 2.0};
  double frame_timeout_s =
      20;  // wall seconds a frame may be late: beyond exposure + readout + download
           // after its trigger, or after the camera's previous frame when frames queue
  double move_timeout_s = 60;  // wall seconds beyond the move's expected duration
  double min_free_mb =
      200;  // keep at least this much free on the capture's disk (1 MB = 10^6 bytes)
  int png_compression = 1;        // 0-9 for raw frames stored as PNG
  uint64_t MinFreeBytes() const;  // min_free_mb in bytes; UINT64_MAX when larger
};

// Reads `plan`, `retries` and `storage` from the rig config root, checking
// camera and light names against `devices`. Errors name file, line and field.
Result<CapturePlan> ReadCapturePlan(const ConfigNode& root, const DeviceSet& devices);
Result<CapturePolicies> ReadCapturePolicies(const ConfigNode& root);

// Bytes the capture's disk must have free before shooting `views` (indices
// into plan.views; on a resume, the views without a verified frame): each
// view's frame at its largest (its camera's width x height x bytes per pixel
// of the plan's format, at least 1; PNG stores raw pixels smaller) plus
// policies.MinFreeBytes(). UINT64_MAX when larger. Every view's camera must be
// in `devices` (ReadCapturePlan checked the plan against them).
uint64_t BytesNeededToFinish(const CapturePlan& plan, const DeviceSet& devices,
                             const std::vector<int>& views, const CapturePolicies& policies);

// Wall seconds a stop takes at least: the move from `from_deg` (none when it is
// within the table's resolution) and its settle, then the longest exposure of
// the stop's cameras, each at its device's own time scale. The stop's cameras
// must be in `devices`.
double StopLowerBoundS(const CapturePlan& plan, const DeviceSet& devices, double from_deg,
                       const PlannedStop& stop);
// The plan's stops in order from `from_deg` (0: a homed table): the physical
// lower bound of a whole capture, without the last frame's download.
double PlanLowerBoundS(const CapturePlan& plan, const DeviceSet& devices, double from_deg = 0);

}  // namespace hairrig
