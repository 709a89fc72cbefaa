// Small file helpers shared by every module that writes results.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path);
// Writes `bytes` to `path` atomically: a temporary file in the same folder is
// written, fsync'd and renamed over `path`, so a reader (or a crash) never sees
// half a file under the final name.
Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size);
inline Status WriteFileAtomic(const std::string& path, const std::string& text) {
  return WriteFileAtomic(path, text.data(), text.size());
}
// Lower-case extension without the dot ("hair", "ply"); "" if none.
std::string FileExtension(const std::string& path);

}  // namespace hairrig
