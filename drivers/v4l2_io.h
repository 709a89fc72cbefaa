// The system calls the `v4l2` camera backend makes, behind an interface so
// that tests run the backend against a fake device (sim_hw/sim_v4l2.h).
// SystemV4l2Io() is the real one: open/ioctl/mmap/poll on /dev/video*.
// Calls follow the system calls' conventions: -1 (MAP_FAILED for Mmap) with
// errno set on failure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hairrig {

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;
  virtual std::vector<std::string> ListNodes() = 0;  // "/dev/video0", ... sorted
  // The USB serial of the device behind `node` (sysfs); "" when it has none.
  virtual std::string UsbSerial(const std::string& node) = 0;
  virtual int Open(const std::string& path, int flags) = 0;
  virtual int Close(int fd) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* Mmap(size_t length, int prot, int flags, int fd, int64_t offset) = 0;
  virtual int Munmap(void* address, size_t length) = 0;
  // Waits until `fd` has a frame to dequeue: 1 ready, 0 timeout, -1 error.
  virtual int PollReadable(int fd, int timeout_ms) = 0;
};

std::shared_ptr<V4l2Io> SystemV4l2Io();

}  // namespace hairrig
