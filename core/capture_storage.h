// Where a capture's files are written. The capture dataset
// (rig/capture_dataset.h) makes every write through one CaptureStorage:
// frames, config snapshot and capture.json (WriteFileAtomic), journal records
// (AppendDurably), the manifest (WriteFileAtomic), the other files of the
// folder (the contact sheet; the simulated rig's ground truth, handed a
// FileWriter), and asks it for the free space (FreeBytes).
// PosixCaptureStorage is the file system itself; the simulated rig plugs in a
// disk that fills up (sim_hw/quota_storage.h), whose failures are the errors a
// full disk gives, with the same messages.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/file_util.h"
#include "core/status.h"

namespace hairrig {

class CaptureStorage {
 public:
  virtual ~CaptureStorage() = default;
  // Writes `size` bytes to `path` atomically, as WriteFileAtomic in
  // core/file_util.h: `path` holds the old file or the new one, never a part.
  // IoError names `path` and the errno ("No space left on device").
  virtual Status WriteFileAtomic(const std::string& path, const void* data, size_t size,
                                 const StageHook& on_stage) = 0;
  // Appends `size` bytes to `fd` (opened O_APPEND; `path` names it) and
  // fdatasyncs it, as AppendDurably in core/file_util.h: after an IoError the
  // file is as it was before the call.
  virtual Status AppendDurably(int fd, const std::string& path, const void* data, size_t size,
                               const StageHook& on_stage) = 0;
  // Bytes an unprivileged writer can still write on the file system holding
  // the existing folder `dir`; IoError naming `dir` if it cannot be read.
  virtual Result<uint64_t> FreeBytes(const std::string& dir) const = 0;
};

// The file system: core/file_util.h's writers with write(2), statvfs(3) for
// the free space (f_bavail blocks of f_frsize bytes).
class PosixCaptureStorage : public CaptureStorage {
 public:
  Status WriteFileAtomic(const std::string& path, const void* data, size_t size,
                         const StageHook& on_stage) override;
  Status AppendDurably(int fd, const std::string& path, const void* data, size_t size,
                       const StageHook& on_stage) override;
  Result<uint64_t> FreeBytes(const std::string& dir) const override;
};

// A PosixCaptureStorage shared by everyone who needs the file system.
std::shared_ptr<CaptureStorage> DefaultCaptureStorage();

// Writes `size` bytes to `path` atomically, as WriteFileAtomic in
// core/file_util.h does. How a writer that does not know where its files
// land (the simulated rig's ground truth) is handed a capture folder's
// storage and its free-space check (rig/capture.h CaptureFolder): the Status
// is the write's, or the check's refusal.
using FileWriter = std::function<Status(const std::string& path, const void* data, size_t size)>;
// `write`'s write, or core/file_util.h's WriteFileAtomic when `write` is empty.
Status WriteFileWith(const FileWriter& write, const std::string& path, const void* data,
                     size_t size);

}  // namespace hairrig
