// The hand-off from capture to the pipeline: a stage that wants each frame as
// soon as it is stored (calibration detects tags during the capture) implements
// FrameSink. Free of device types: a sink sees the stored file, its pixels and
// where the view was taken, whether the frame came from a live rig, the
// simulated one or a replay.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace hairrig {

struct StoredFrame {
  int view = 0;             // index in the capture plan
  int stop = 0;             // turntable stop
  std::string camera_name;  // role in the rig config ("upper")
  std::string camera_serial;
  std::string path;  // absolute path of the stored, verified file
  std::string sha256;
  double turntable_commanded_deg = 0;
  double turntable_measured_deg = 0;
  cv::Mat image;  // decoded pixels: 8-bit BGR or single channel
};

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // Called once per stored frame, from a capture worker thread, possibly from
  // several threads at once; must be thread-safe and should return quickly
  // (queue heavy work). A sink cannot fail the capture.
  virtual void OnFrameStored(const StoredFrame& frame) = 0;
  // Called once after the last frame of a session.
  virtual void OnCaptureFinished() {}
};

// Hands each frame to several sinks, in the order they were added.
class FrameSinks : public FrameSink {
 public:
  void Add(FrameSink* sink) {
    if (sink) sinks_.push_back(sink);
  }
  bool empty() const { return sinks_.empty(); }
  void OnFrameStored(const StoredFrame& frame) override {
    for (FrameSink* sink : sinks_) sink->OnFrameStored(frame);
  }
  void OnCaptureFinished() override {
    for (FrameSink* sink : sinks_) sink->OnCaptureFinished();
  }

 private:
  std::vector<FrameSink*> sinks_;
};

}  // namespace hairrig
