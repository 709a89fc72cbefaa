#include "drivers/v4l2_io.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

class SystemIo : public V4l2Io {
 public:
  std::vector<std::string> ListNodes() override {
    std::vector<std::string> nodes;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator("/dev", ec)) {
      if (entry.path().filename().string().rfind("video", 0) == 0)
        nodes.push_back(entry.path().string());
    }
    std::sort(nodes.begin(), nodes.end());
    return nodes;
  }
  // The `serial` attribute of the first ancestor of the node's sysfs device that has one.
  std::string UsbSerial(const std::string& node) override {
    std::error_code ec;
    fs::path dir = fs::canonical(
        fs::path("/sys/class/video4linux") / fs::path(node).filename() / "device", ec);
    for (int depth = 0; !ec && depth < 4 && dir.has_parent_path();
         ++depth, dir = dir.parent_path()) {
      if (!fs::exists(dir / "serial")) continue;
      std::ifstream in(dir / "serial");
      std::string serial;
      std::getline(in, serial);
      return serial;
    }
    return "";
  }
  int Open(const std::string& path, int flags) override {
    return open(path.c_str(), flags | O_CLOEXEC);
  }
  int Close(int fd) override { return close(fd); }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    int r = 0;
    do {
      r = ioctl(fd, request, arg);
    } while (r == -1 && errno == EINTR);
    return r;
  }
  void* Mmap(size_t length, int prot, int flags, int fd, int64_t offset) override {
    return mmap(nullptr, length, prot, flags, fd, static_cast<off_t>(offset));
  }
  int Munmap(void* address, size_t length) override { return munmap(address, length); }
  int PollReadable(int fd, int timeout_ms) override {
    pollfd p{fd, POLLIN, 0};
    int r = 0;
    do {
      r = poll(&p, 1, timeout_ms);
    } while (r == -1 && errno == EINTR);
    if (r > 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL))) {
      errno = ENODEV;
      return -1;
    }
    return r;
  }
};

}  // namespace

std::shared_ptr<V4l2Io> SystemV4l2Io() { return std::make_shared<SystemIo>(); }

}  // namespace hairrig
