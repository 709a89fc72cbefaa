#include "core/file_util.h"

#include <atomic>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

namespace hairrig {

Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return NotFound(path + ": cannot open for reading (" + std::strerror(errno) + ")");
  const std::streamsize size = in.tellg();
  if (size < 0) return IoError(path + ": cannot determine the file size");
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  in.seekg(0);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size)) {
    return IoError(path + ": read failed");
  }
  return bytes;
}

Status SyncFolder(const std::string& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return IoError(folder + ": cannot open the folder to sync it (" + std::strerror(errno) + ")");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) return IoError(folder + ": fsync failed (" + std::strerror(errno) + ")");
  return Status::Ok();
}

Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size,
                       const std::function<void(const char* stage)>& on_stage) {
  // Unique per process and per call, so that two threads writing one path never share a temporary.
  static std::atomic<uint64_t> next_temporary{0};
  const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(next_temporary++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return IoError(tmp + ": cannot create (" + std::strerror(errno) + ")");
  const auto* p = static_cast<const uint8_t*>(bytes);
  size_t left = size;
  bool reported_half = !on_stage;
  while (left > 0) {
    if (!reported_half && left <= size / 2) {
      on_stage("half_written");
      reported_half = true;
    }
    const size_t chunk = reported_half ? left : left - size / 2;
    const ssize_t n = ::write(fd, p, chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return IoError(path + ": write failed (" + why + ")");
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    ::unlink(tmp.c_str());
    return IoError(path + ": fsync/close failed (" + std::strerror(errno) + ")");
  }
  if (on_stage) on_stage("before_rename");
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    return IoError(path + ": rename into place failed (" + why + ")");
  }
  const size_t slash = path.find_last_of('/');
  return SyncFolder(slash == std::string::npos ? "." : path.substr(0, slash == 0 ? 1 : slash));
}

std::string FileExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace hairrig
