#include "drivers/uvc_discovery.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string FirstLine(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

// The USB serial of the device behind /sys/class/video4linux/<node>: the
// `serial` attribute of the first ancestor that has one.
std::string UsbSerial(const std::string& node) {
  std::error_code ec;
  fs::path dir = fs::canonical(fs::path("/sys/class/video4linux") / node / "device", ec);
  for (int depth = 0; !ec && depth < 4 && dir.has_parent_path(); ++depth, dir = dir.parent_path()) {
    if (fs::exists(dir / "serial")) return FirstLine(dir / "serial");
  }
  return "";
}

}  // namespace

std::vector<V4l2Detected> DetectV4l2Cameras() {
  std::vector<V4l2Detected> found;
  std::error_code ec;
  std::vector<std::string> nodes;
  for (const auto& entry : fs::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) nodes.push_back(name);
  }
  std::sort(nodes.begin(), nodes.end());
  for (const std::string& node : nodes) {
    V4l2Detected d;
    d.path = "/dev/" + node;
    const int fd = open(d.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      d.error = std::string("cannot open: ") + std::strerror(errno) + " (is the user in the video group?)";
      found.push_back(d);
      continue;
    }
    v4l2_capability caps{};
    const int r = ioctl(fd, VIDIOC_QUERYCAP, &caps);
    close(fd);
    if (r != 0) {
      d.error = std::string("VIDIOC_QUERYCAP failed: ") + std::strerror(errno);
      found.push_back(d);
      continue;
    }
    const uint32_t device_caps = (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
    if (!(device_caps & V4L2_CAP_VIDEO_CAPTURE)) continue;  // metadata or output node
    d.card = reinterpret_cast<const char*>(caps.card);
    d.driver = reinterpret_cast<const char*>(caps.driver);
    d.bus_info = reinterpret_cast<const char*>(caps.bus_info);
    d.serial = UsbSerial(node);
    found.push_back(d);
  }
  return found;
}

}  // namespace hairrig
