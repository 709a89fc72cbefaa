// SHA-256 (FIPS 180-4) of byte buffers and files: the integrity check of every
// stored frame (rig/capture_dataset.h). Incremental, so a frame can be hashed
// while it is written.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/file_util.h"
#include "core/status.h"

namespace hairrig {

class Sha256 {
 public:
  Sha256();
  void Update(const void* data, size_t size);
  // Finishes and returns the digest as 64 lower-case hex characters. The
  // object must not be updated afterwards.
  std::string HexDigest();

 private:
  void Compress(const uint8_t* block);

  std::array<uint32_t, 8> state_;
  std::array<uint8_t, 64> buffer_{};
  size_t buffered_ = 0;
  uint64_t total_bytes_ = 0;
};

std::string Sha256Hex(const void* data, size_t size);
// Of a regular file of at most `max_bytes` (core/file_util.h ReadFileChunks:
// errors name the file; a folder, FIFO or device is refused, never read).
// `bytes_hashed`, when given, receives the number of bytes hashed.
Result<std::string> Sha256OfFile(const std::string& path, uint64_t max_bytes = kMaxFileBytes,
                                 uint64_t* bytes_hashed = nullptr);

}  // namespace hairrig
