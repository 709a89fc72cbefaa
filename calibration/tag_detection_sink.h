// Tag detection during a capture: a FrameSink that detects
// and matches the box's tags on each frame as soon as it is stored, on its own
// worker threads, so that when the last frame lands most of the calibration's
// detection is done. CalibrationFrame::observations takes the results.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "calibration/apriltag_detector.h"
#include "calibration/view_pose.h"
#include "core/calib_box.h"
#include "core/frame_sink.h"

namespace hairrig {

// The key WaitForAll files a frame's detections under: its canonical path
// (the path itself when it cannot be resolved).
std::string DetectionKey(const std::string& frame_path);

class TagDetectionSink : public FrameSink {
 public:
  // `threads` workers (at least 1), each with its own detector.
  TagDetectionSink(CalibBox box, TagDetectorOptions detector, int threads);
  ~TagDetectionSink() override;  // stops the workers; queued frames are dropped

  // Queues the frame (its pixels are shared, not copied); never blocks on detection.
  void OnFrameStored(const StoredFrame& frame) override;

  // Waits until every queued frame is detected, then returns the matched
  // tags by DetectionKey of the stored file. A frame whose detection failed
  // is absent (the calibration then reads it again and names the fault).
  std::map<std::string, ViewObservations> WaitForAll();

  // Steady-clock time (ns) the last frame was handed over; 0 before any.
  int64_t last_frame_ns() const;
  // Steady-clock time (ns) the last detection finished; 0 before any.
  int64_t last_detected_ns() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
