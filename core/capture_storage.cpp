#include "core/capture_storage.h"

#include <sys/statvfs.h>

#include <cerrno>

namespace hairrig {

Status PosixCaptureStorage::WriteFileAtomic(const std::string& path, const void* data, size_t size,
                                            const StageHook& on_stage) {
  return ::hairrig::WriteFileAtomic(path, data, size, on_stage);
}

Status PosixCaptureStorage::AppendDurably(int fd, const std::string& path, const void* data,
                                          size_t size, const StageHook& on_stage) {
  return ::hairrig::AppendDurably(fd, path, data, size, on_stage);
}

Result<uint64_t> PosixCaptureStorage::FreeBytes(const std::string& dir) const {
  struct statvfs st {};
  if (::statvfs(dir.c_str(), &st) != 0)
    return IoErrorFromErrno(dir + ": cannot read the free space", errno);
  return static_cast<uint64_t>(st.f_bavail) * st.f_frsize;
}

std::shared_ptr<CaptureStorage> DefaultCaptureStorage() {
  static const std::shared_ptr<CaptureStorage> storage = std::make_shared<PosixCaptureStorage>();
  return storage;
}

Status WriteFileWith(const FileWriter& write, const std::string& path, const void* data,
                     size_t size) {
  return write ? write(path, data, size) : ::hairrig::WriteFileAtomic(path, data, size);
}

}  // namespace hairrig
