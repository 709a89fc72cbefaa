// Small file helpers shared by every module that reads inputs or writes results.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// The largest file ReadFileBytes reads unless told otherwise (frames, strand
// files, meshes): 2 GiB.
inline constexpr uint64_t kMaxFileBytes = uint64_t{2} << 30;

// A file descriptor closed when it goes out of scope: how a caller holds the
// descriptor OpenRegularFileForRead or OpenRegularFileForAppend returns.
//
//   HR_ASSIGN_OR_RETURN(const int opened, OpenRegularFileForRead(path));
//   const ScopedFd fd(opened);  // closed on every return below
class ScopedFd {
 public:
  ScopedFd() = default;
  explicit ScopedFd(int fd) : fd_(fd) {}
  ~ScopedFd() { reset(-1); }
  ScopedFd(const ScopedFd&) = delete;
  ScopedFd& operator=(const ScopedFd&) = delete;
  int get() const { return fd_; }
  // Gives up ownership without closing.
  void release() { fd_ = -1; }
  // Closes the descriptor held (if any) and holds `fd`.
  void reset(int fd);

 private:
  int fd_ = -1;
};

// Reads a regular file (a symlink to one is followed) in order, passing each
// chunk of up to 64 KiB to `chunk`. Never blocks on opening and never reads
// anything but a regular file: InvalidArgument names the file and what it is
// (a folder, a FIFO, a device such as /dev/zero, a socket); OutOfRange when it
// holds more than `max_bytes`, checked before the first read and while reading;
// NotFound / IoError name the file.
Status ReadFileChunks(const std::string& path, uint64_t max_bytes,
                      const std::function<void(const uint8_t* data, size_t size)>& chunk);
// The whole file, with the checks of ReadFileChunks.
Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path,
                                           uint64_t max_bytes = kMaxFileBytes);
Result<std::string> ReadFileText(const std::string& path, uint64_t max_bytes);
// Opens `path` for reading with the checks of ReadFileChunks (a regular file
// only, never blocking on opening, at most `max_bytes`) and returns the
// descriptor, which the caller closes; for readers that need only some of the
// file (pread at the offsets they choose).
Result<int> OpenRegularFileForRead(const std::string& path, uint64_t max_bytes = kMaxFileBytes);
// Opens `path` for appending (O_APPEND, created with mode 0644 when absent,
// never through a symlink) and returns the descriptor, which the caller closes.
// Never blocks on opening and never opens anything but a regular file:
// InvalidArgument names the file and what it is (a folder, a FIFO, a device, a
// socket), as ReadFileChunks does; IoError names the file and the errno.
Result<int> OpenRegularFileForAppend(const std::string& path);
// IoError "<what> (<strerror(error_number)>)", e.g. "<path>: write failed (No
// space left on device)": the one message every writer here builds from errno.
Status IoErrorFromErrno(const std::string& what, int error_number);
// The write(2) the writers below call: writes up to `size` bytes, returns how
// many, or -1 with errno set. Empty: ::write. A stand-in keeps that contract
// (a full disk: some bytes, then -1 with errno ENOSPC).
using WriteCall = std::function<ssize_t(int fd, const void* data, size_t size)>;
// Called with the name of a stage a writer reached; crash-safety tests stop
// the process there.
using StageHook = std::function<void(const char* stage)>;
// Writes `bytes` to `path` atomically: a temporary file in the same folder is
// written, fsync'd and renamed over `path`, so a reader (or a crash) never sees
// half a file under the final name.
// The folder is fsync'd after the rename so the new name survives power loss.
// The temporary is created anew (never through an existing name or symlink),
// and the rename replaces a symlink at `path` instead of writing through it.
// On failure the temporary is removed and `path` is as it was; IoError names
// `path` and the errno (IoErrorFromErrno).
// `on_stage`, when given, is called with "half_written" and "before_rename".
Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size,
                       const StageHook& on_stage = {}, const WriteCall& write_call = {});
// Appends `size` bytes to `fd`, a file opened with O_APPEND that `path` names
// in messages, and fdatasyncs it. `on_stage`, when given, is called with
// "half_written" once the first half is written. A failed append (IoError
// naming `path` and the errno) cuts the file back to its length before the
// call, so no part of the bytes stays in it; only a crash can leave a part.
Status AppendDurably(int fd, const std::string& path, const void* bytes, size_t size,
                     const StageHook& on_stage = {}, const WriteCall& write_call = {});
// fsync of a folder, so that renames and new entries in it are durable.
Status SyncFolder(const std::string& folder);
inline Status WriteFileAtomic(const std::string& path, const std::string& text) {
  return WriteFileAtomic(path, text.data(), text.size());
}
// Lower-case extension without the dot ("hair", "ply"); "" if none.
std::string FileExtension(const std::string& path);
// True if `path` lies inside `folder` after both are made absolute and
// lexically normalised (no "..", no absolute escape). Symlinks are not
// followed: ResolveInside does that.
bool PathIsInside(const std::string& path, const std::string& folder);
// `path` with every symlink on the way resolved, if it then lies inside
// `folder` (resolved the same way); CorruptData naming `path` and where it
// leads otherwise, IoError when it cannot be resolved. A symlink that points
// out of a folder (to /dev/zero, to another capture) is caught here before
// anything reads it.
Result<std::string> ResolveInside(const std::string& path, const std::string& folder);

}  // namespace hairrig
