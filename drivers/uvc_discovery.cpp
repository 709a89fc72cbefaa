#include "drivers/uvc_discovery.h"

#include <fcntl.h>
#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>

#include "drivers/v4l2_io.h"

namespace hairrig {

std::vector<V4l2Detected> DetectV4l2Cameras(V4l2Io& io) {
  std::vector<V4l2Detected> found;
  for (const std::string& node : io.ListNodes()) {
    V4l2Detected d;
    d.path = node;
    const int fd = io.Open(node, O_RDWR | O_NONBLOCK);
    if (fd < 0) {
      d.error = std::string("cannot open: ") + std::strerror(errno) +
                " (is the user in the video group?)";
      found.push_back(d);
      continue;
    }
    v4l2_capability caps{};
    const int r = io.Ioctl(fd, VIDIOC_QUERYCAP, &caps);
    const int saved = errno;
    io.Close(fd);
    if (r != 0) {
      d.error = std::string("VIDIOC_QUERYCAP failed: ") + std::strerror(saved);
      found.push_back(d);
      continue;
    }
    const uint32_t device_caps =
        (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
    if (!(device_caps & V4L2_CAP_VIDEO_CAPTURE)) continue;  // metadata or output node
    d.card = reinterpret_cast<const char*>(caps.card);
    d.driver = reinterpret_cast<const char*>(caps.driver);
    d.bus_info = reinterpret_cast<const char*>(caps.bus_info);
    d.serial = io.UsbSerial(node);
    found.push_back(d);
  }
  return found;
}

std::vector<V4l2Detected> DetectV4l2Cameras() {
  auto io = SystemV4l2Io();
  return DetectV4l2Cameras(*io);
}

}  // namespace hairrig
