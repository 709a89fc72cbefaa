// A fake UVC camera behind the `v4l2` backend's system-call layer
// (drivers/v4l2_io.h): one /dev/video node answering the ioctls the backend
// uses (QUERYCAP, ENUM_FMT, S_FMT, REQBUFS, QUERYBUF, QBUF, DQBUF,
// STREAMON/OFF, QUERYCTRL, S_CTRL), mmap'd buffers and poll, with the
// rendered world as its picture.
//
// Like a real UVC camera it streams continuously once STREAMON: every frame
// period (1/fps device seconds, times the world's time_scale) it fills the
// oldest queued buffer with the world as it is then, stamped with the steady
// clock (CLOCK_MONOTONIC, as V4L2 does); with no buffer queued the frame is
// dropped. The picture is rendered when the buffer is dequeued, from the
// world state latched at its timestamp, so frames nobody reads cost nothing.
// It offers one size (the scene camera's) in MJPEG and YUYV; S_FMT answers
// that size whatever is asked, as drivers do.
//
// Faults: Unplug() makes every call fail with ENODEV (and the node vanish
// from ListNodes) until Replug(); CorruptNextFrames(n): the next n frames
// the camera takes are truncated MJPEG that does not decode.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "core/status.h"
#include "drivers/v4l2_io.h"

namespace hairrig {

class SimWorld;

struct SimV4l2Options {
  std::string serial;    // the USB serial sysfs reports
  int scene_camera = 0;  // the scene camera whose view it shows
  std::string node = "/dev/video0";
  double fps = 30;  // frames per device second

  // InvalidArgument naming the field: a negative scene_camera, an empty
  // node, an fps that is not finite and positive.
  Status Check() const;
};

class SimV4l2Device : public V4l2Io {
 public:
  SimV4l2Device(std::shared_ptr<SimWorld> world, SimV4l2Options options);
  ~SimV4l2Device() override;

  std::vector<std::string> ListNodes() override;
  std::string UsbSerial(const std::string& node) override;
  int Open(const std::string& path, int flags) override;
  int Close(int fd) override;
  int Ioctl(int fd, unsigned long request, void* arg) override;
  void* Mmap(size_t length, int prot, int flags, int fd, int64_t offset) override;
  int Munmap(void* address, size_t length) override;
  int PollReadable(int fd, int timeout_ms) override;

  void Unplug();
  void Replug();
  void CorruptNextFrames(int count);
  // Waits until every buffer queued to the camera holds a frame (none is
  // waiting to be filled); false if that has not happened within `timeout`.
  bool WaitUntilQueuedBuffersFilled(std::chrono::milliseconds timeout);
  int frames_delivered() const;  // dequeued with a picture
  int frames_dropped() const;    // no queued buffer at the frame's time

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
