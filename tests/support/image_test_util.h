// Test helpers shared by the tests of image readers: image files written byte
// by byte, so a test can claim any size without allocating it.
#pragma once

#include <cstdint>
#include <string>

namespace hairrig {

// CRC-32 (ISO-HDLC, the one PNG chunks carry) of `bytes`.
inline uint32_t PngCrc32(const std::string& bytes) {
  uint32_t crc = 0xFFFFFFFFu;
  for (const unsigned char b : bytes) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

// A PNG chunk: length, type, data, CRC.
inline std::string PngChunk(const std::string& type, const std::string& data) {
  const auto be32 = [](uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 8), static_cast<char>(v)};
  };
  return be32(static_cast<uint32_t>(data.size())) + type + data + be32(PngCrc32(type + data));
}

// A PNG of `width` x `height` RGB pixels with an empty IDAT: valid up to the
// pixel data, so a header reader and OpenCV's own size check see the claimed
// size, and decoding it fails.
inline std::string PngClaiming(uint32_t width, uint32_t height) {
  std::string ihdr;
  for (const uint32_t v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) ihdr += static_cast<char>(v >> shift);
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, no filter, no interlace
  return std::string("\x89PNG\r\n\x1a\n", 8) + PngChunk("IHDR", ihdr) + PngChunk("IDAT", "") +
         PngChunk("IEND", "");
}

}  // namespace hairrig
