// Small file helpers shared by every module that writes results.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// The largest file ReadFileBytes reads unless told otherwise (frames, strand
// files, meshes): 2 GiB.
inline constexpr uint64_t kMaxFileBytes = uint64_t{2} << 30;

// Reads a regular file (a symlink to one is followed) in order, passing each
// chunk of up to 64 KiB to `chunk`. Never blocks on opening and never reads
// anything but a regular file: InvalidArgument names the file and what it is
// (a folder, a FIFO, a device such as /dev/zero, a socket); OutOfRange when it
// holds more than `max_bytes`, checked before the first read and while reading;
// NotFound / IoError name the file.
Status ReadFileChunks(const std::string& path, uint64_t max_bytes,
                      const std::function<void(const uint8_t* data, size_t size)>& chunk);
// The whole file, with the checks of ReadFileChunks.
Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path, uint64_t max_bytes = kMaxFileBytes);
Result<std::string> ReadFileText(const std::string& path, uint64_t max_bytes);
// Writes `bytes` to `path` atomically: a temporary file in the same folder is
// written, fsync'd and renamed over `path`, so a reader (or a crash) never sees
// half a file under the final name.
// The folder is fsync'd after the rename so the new name survives power loss.
// The temporary is created anew (never through an existing name or symlink),
// and the rename replaces a symlink at `path` instead of writing through it.
// `on_stage`, when given, is called with "half_written" and "before_rename"
// (crash-safety tests stop the process there).
Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size,
                       const std::function<void(const char* stage)>& on_stage = {});
// fsync of a folder, so that renames and new entries in it are durable.
Status SyncFolder(const std::string& folder);
inline Status WriteFileAtomic(const std::string& path, const std::string& text) {
  return WriteFileAtomic(path, text.data(), text.size());
}
// Lower-case extension without the dot ("hair", "ply"); "" if none.
std::string FileExtension(const std::string& path);

}  // namespace hairrig
