// A capture disk of limited size, for the simulated rig (the sim fault
// disk_full, sim_hw/sim_faults.h) and tests. Every write goes to the real file
// through core/file_util.h's writers; the limit acts inside their write(2):
// once the disk is full, a write puts in the bytes that still fit and the next
// one fails with errno ENOSPC, as the kernel's does. The caller meets the
// IoError of a real full disk, with its message ("No space left on device"),
// and its clean-up runs as it would (the temporary of an atomic write
// removed, a failed append cut back).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <mutex>
#include <string>

#include "core/capture_storage.h"

namespace hairrig {

struct QuotaStorageOptions {
  // Bytes the files written through the storage may occupy at once. A file
  // replaced, or the temporary of a failed write, gives its bytes back.
  uint64_t quota_bytes = std::numeric_limits<uint64_t>::max();
  // Frame files (files written into a folder named `frames`) the disk holds:
  // the write of every later frame file fails with ENOSPC after half its
  // bytes, counted in the order the writes start. Other files (journal
  // records, manifest) still fit, as on a disk with a few kilobytes left.
  // FreeBytes does not show this limit: the write fails where the free space
  // looked sufficient, as when another program fills the disk between a
  // check and the write. -1: no limit.
  int frame_files = -1;

  // InvalidArgument naming frame_files below -1 (every quota_bytes is valid).
  Status Check() const;
};

// Bad options (QuotaStorageOptions::Check) fail every write with their error.
class QuotaStorage : public PosixCaptureStorage {
 public:
  explicit QuotaStorage(const QuotaStorageOptions& options) : options_(options) {}

  Status WriteFileAtomic(const std::string& path, const void* data, size_t size,
                         const StageHook& on_stage) override;
  Status AppendDurably(int fd, const std::string& path, const void* data, size_t size,
                       const StageHook& on_stage) override;
  // What is left of the quota, at most the real file system's free bytes.
  Result<uint64_t> FreeBytes(const std::string& dir) const override;

  // Takes `bytes` of the quota, as another program writing to the same disk does.
  void Consume(uint64_t bytes);
  // Bytes taken: the files written through the storage, and Consume.
  uint64_t used_bytes() const;

 private:
  // One WriteFileAtomic or AppendDurably call: the bytes it may still write
  // and the bytes it wrote (given back when it fails).
  struct Call {
    uint64_t budget = std::numeric_limits<uint64_t>::max();
    uint64_t written = 0;
  };
  // write(2) within the quota and the call's budget; -1 with errno ENOSPC
  // when not a byte fits.
  ssize_t Write(Call* call, int fd, const void* data, size_t size);
  void Finish(const Call& call, const Status& result);
  uint64_t LeftLocked() const {
    return used_ < options_.quota_bytes ? options_.quota_bytes - used_ : 0;
  }

  const QuotaStorageOptions options_;
  mutable std::mutex mutex_;
  uint64_t used_ = 0;
  std::map<std::string, uint64_t> files_;  // path -> bytes, of the files written here
  int frame_files_started_ = 0;
};

}  // namespace hairrig
