// Small file helpers shared by every module that writes results.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path);
// Writes `bytes` to `path` atomically: a temporary file in the same folder is
// written, fsync'd and renamed over `path`, so a reader (or a crash) never sees
// half a file under the final name.
// The folder is fsync'd after the rename so the new name survives power loss.
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
