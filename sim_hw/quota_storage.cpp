#include "sim_hw/quota_storage.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>

namespace hairrig {

namespace {

bool IsFrameFile(const std::string& path) {
  return std::filesystem::path(path).parent_path().filename() == "frames";
}

}  // namespace

Status QuotaStorageOptions::Check() const {
  if (frame_files < -1) {
    return InvalidArgument("frame_files must be -1 (no limit) or more, got " +
                           std::to_string(frame_files));
  }
  return Status::Ok();
}

Status QuotaStorage::WriteFileAtomic(const std::string& path, const void* data, size_t size,
                                     const StageHook& on_stage) {
  HR_RETURN_IF_ERROR(options_.Check().WithContext("quota storage"));
  Call call;
  if (options_.frame_files >= 0 && IsFrameFile(path)) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (++frame_files_started_ > options_.frame_files) call.budget = size / 2;
  }
  const Status s = ::hairrig::WriteFileAtomic(
      path, data, size, on_stage,
      [this, &call](int fd, const void* p, size_t n) { return Write(&call, fd, p, n); });
  Finish(call, s);
  if (s.ok()) {
    std::lock_guard<std::mutex> lock(mutex_);
    uint64_t& bytes = files_[path];
    used_ -= std::min(used_, bytes);  // the file it replaced
    bytes = size;
  }
  return s;
}

Status QuotaStorage::AppendDurably(int fd, const std::string& path, const void* data, size_t size,
                                   const StageHook& on_stage) {
  HR_RETURN_IF_ERROR(options_.Check().WithContext("quota storage"));
  Call call;
  const Status s = ::hairrig::AppendDurably(
      fd, path, data, size, on_stage,
      [this, &call](int f, const void* p, size_t n) { return Write(&call, f, p, n); });
  Finish(call, s);
  if (s.ok()) {
    std::lock_guard<std::mutex> lock(mutex_);
    files_[path] += size;
  }
  return s;
}

// A failed call's bytes are gone from the disk: the temporary was removed or
// the file cut back.
void QuotaStorage::Finish(const Call& call, const Status& result) {
  if (result.ok()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  used_ -= std::min(used_, call.written);
}

ssize_t QuotaStorage::Write(Call* call, int fd, const void* data, size_t size) {
  size_t n = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    n = static_cast<size_t>(std::min<uint64_t>({size, LeftLocked(), call->budget - call->written}));
    if (n == 0 && size > 0) {
      errno = ENOSPC;
      return -1;
    }
    used_ += n;  // taken while the write runs, so that two writes never share the last bytes
  }
  const ssize_t written = ::write(fd, data, n);
  const int error_number = errno;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const size_t landed = written > 0 ? static_cast<size_t>(written) : 0;
    used_ -= n - landed;
    call->written += landed;
  }
  errno = error_number;
  return written;
}

Result<uint64_t> QuotaStorage::FreeBytes(const std::string& dir) const {
  HR_ASSIGN_OR_RETURN(const uint64_t real, PosixCaptureStorage::FreeBytes(dir));
  std::lock_guard<std::mutex> lock(mutex_);
  return std::min(real, LeftLocked());
}

void QuotaStorage::Consume(uint64_t bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  used_ += bytes;
}

uint64_t QuotaStorage::used_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return used_;
}

}  // namespace hairrig
