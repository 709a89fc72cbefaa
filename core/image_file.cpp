#include "core/image_file.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <string_view>

#include "core/file_util.h"

namespace hairrig {
namespace {

using namespace std::string_view_literals;

// The most JPEG segments (and fill bytes) walked before the frame header.
constexpr int kMaxJpegSegments = 4096;
// The most entries read from a TIFF directory.
constexpr uint64_t kMaxTiffEntries = 4096;
// How far into a PNM file its width and height are looked for.
constexpr size_t kPnmHeaderBytes = 4096;

// Copies up to `size` bytes of an encoded image at `offset` into `out` and
// returns how many there were (fewer at the image's end, 0 past it).
using ByteSource = std::function<Result<size_t>(uint64_t offset, size_t size, uint8_t* out)>;

// An encoded image being parsed: its bytes and its name for messages.
struct Source {
  const ByteSource& read;
  const std::string& name;

  // Exactly `size` bytes at `offset`; CorruptData naming the file and `what` when it ends first.
  Result<std::vector<uint8_t>> Exactly(uint64_t offset, size_t size,
                                       const std::string& what) const {
    std::vector<uint8_t> out(size);
    HR_ASSIGN_OR_RETURN(const size_t got, read(offset, size, out.data()));
    if (got < size) return Corrupt("the image ends inside its " + what);
    return out;
  }
  Status Corrupt(const std::string& what) const { return CorruptData(name + ": " + what); }
};

// The unsigned integer in the `n` bytes at `p`.
uint64_t Unsigned(const uint8_t* p, int n, bool big_endian) {
  uint64_t v = 0;
  for (int k = 0; k < n; ++k) v = (v << 8) | p[big_endian ? k : n - 1 - k];
  return v;
}

// IHDR, the chunk every PNG starts with: width and height, big-endian.
Result<ImageHeader> PngHeader(const Source& s) {
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> b, s.Exactly(0, 24, "PNG IHDR chunk"));
  if (std::memcmp(&b[12], "IHDR", 4) != 0) return s.Corrupt("PNG whose first chunk is not IHDR");
  return ImageHeader{"PNG", Unsigned(&b[16], 4, true), Unsigned(&b[20], 4, true)};
}

// SOF0..SOF15 but DHT (C4), JPG (C8) and DAC (CC): the frame header.
bool IsJpegFrameMarker(uint8_t marker) {
  return marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
}

// The segments after SOI walked by their lengths up to the frame header
// (precision, height, width).
Result<ImageHeader> JpegHeader(const Source& s) {
  uint64_t at = 2;
  for (int segment = 0; segment < kMaxJpegSegments; ++segment) {
    HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> marker, s.Exactly(at, 2, "JPEG markers"));
    if (marker[0] != 0xFF)
      return s.Corrupt("no JPEG marker at byte " + std::to_string(at) + " where one belongs");
    if (marker[1] == 0xFF) {  // a fill byte
      ++at;
      continue;
    }
    at += 2;
    const uint8_t m = marker[1];
    if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) continue;  // markers without a length
    if (m == 0xD9 || m == 0xDA) return s.Corrupt("JPEG without a frame header before its scan");
    HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> length, s.Exactly(at, 2, "JPEG segments"));
    const uint64_t bytes = Unsigned(length.data(), 2, true);
    if (bytes < 2) return s.Corrupt("JPEG segment at byte " + std::to_string(at) + " of length 0");
    if (IsJpegFrameMarker(m)) {
      HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> frame,
                          s.Exactly(at + 2, 5, "JPEG frame header"));
      return ImageHeader{"JPEG", Unsigned(&frame[3], 2, true), Unsigned(&frame[1], 2, true)};
    }
    at += bytes;
  }
  return s.Corrupt("JPEG with more than " + std::to_string(kMaxJpegSegments) +
                   " segments before its frame header");
}

// ImageWidth (256) and ImageLength (257) of the first directory, classic TIFF
// or BigTIFF, either byte order.
Result<ImageHeader> TiffHeader(const Source& s) {
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> h, s.Exactly(0, 16, "TIFF header"));
  const bool big_endian = h[0] == 'M';
  const bool big_tiff = Unsigned(&h[2], 2, big_endian) == 43;
  const uint64_t directory =
      big_tiff ? Unsigned(&h[8], 8, big_endian) : Unsigned(&h[4], 4, big_endian);
  const int count_bytes = big_tiff ? 8 : 2, value_at = big_tiff ? 12 : 8;
  const size_t entry_bytes = big_tiff ? 20 : 12, value_bytes = big_tiff ? 8 : 4;
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> count,
                      s.Exactly(directory, static_cast<size_t>(count_bytes), "TIFF directory"));
  const uint64_t entries = Unsigned(count.data(), count_bytes, big_endian);
  if (entries > kMaxTiffEntries)
    return s.Corrupt("TIFF directory of " + std::to_string(entries) + " entries");
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> e,
                      s.Exactly(directory + static_cast<uint64_t>(count_bytes),
                                static_cast<size_t>(entries) * entry_bytes, "TIFF directory"));
  ImageHeader header{"TIFF", 0, 0};
  for (size_t k = 0; k < entries; ++k) {
    const uint8_t* entry = &e[k * entry_bytes];
    const uint64_t tag = Unsigned(entry, 2, big_endian), type = Unsigned(entry + 2, 2, big_endian);
    const size_t bytes = type == 3 ? 2 : type == 4 ? 4 : type == 16 ? 8 : 0;  // SHORT, LONG, LONG8
    if (bytes == 0 || bytes > value_bytes || (tag != 256 && tag != 257)) continue;
    const uint64_t value = Unsigned(entry + value_at, static_cast<int>(bytes), big_endian);
    (tag == 256 ? header.width_px : header.height_px) = value;
  }
  if (header.width_px == 0 || header.height_px == 0)
    return s.Corrupt("TIFF without ImageWidth and ImageLength in its first directory");
  return header;
}

// BITMAPCOREHEADER (16-bit sizes) or a later info header (32-bit, a negative
// height for top-down rows).
Result<ImageHeader> BmpHeader(const Source& s) {
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> b, s.Exactly(0, 26, "BMP header"));
  if (Unsigned(&b[14], 4, false) == 12)
    return ImageHeader{"BMP", Unsigned(&b[18], 2, false), Unsigned(&b[20], 2, false)};
  const int64_t width = static_cast<int32_t>(Unsigned(&b[18], 4, false));
  const int64_t height = static_cast<int32_t>(Unsigned(&b[22], 4, false));
  return ImageHeader{"BMP", static_cast<uint64_t>(std::max<int64_t>(width, 0)),
                     static_cast<uint64_t>(height < 0 ? -height : height)};
}

// P1..P6 and PF/Pf: the magic, then width and height in decimal, with white
// space and '#' comments between.
Result<ImageHeader> PnmHeader(const Source& s) {
  std::vector<uint8_t> text(kPnmHeaderBytes);
  HR_ASSIGN_OR_RETURN(const size_t size, s.read(0, text.size(), text.data()));
  size_t at = 2;
  uint64_t numbers[2] = {0, 0};
  for (uint64_t& number : numbers) {
    while (at < size && (std::isspace(text[at]) || text[at] == '#')) {
      if (text[at] == '#') {
        while (at < size && text[at] != '\n') ++at;
      } else {
        ++at;
      }
    }
    size_t digits = 0;
    for (; at < size && std::isdigit(text[at]); ++at, ++digits) {
      if (digits == 12) return s.Corrupt("PNM header with a size of more than 12 digits");
      number = number * 10 + static_cast<uint64_t>(text[at] - '0');
    }
    if (digits == 0)
      return s.Corrupt("PNM header without its width and height in its first " +
                       std::to_string(kPnmHeaderBytes) + " bytes");
  }
  return ImageHeader{"PNM", numbers[0], numbers[1]};
}

// RIFF/WEBP with a VP8 (lossy), VP8L (lossless) or VP8X (extended) first chunk.
Result<ImageHeader> WebpHeader(const Source& s) {
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> b, s.Exactly(0, 30, "WebP header"));
  const std::string_view chunk(reinterpret_cast<const char*>(&b[12]), 4);
  if (chunk == "VP8 " && b[23] == 0x9D && b[24] == 0x01 && b[25] == 0x2A)
    return ImageHeader{"WebP", Unsigned(&b[26], 2, false) & 0x3FFF,
                       Unsigned(&b[28], 2, false) & 0x3FFF};
  if (chunk == "VP8L" && b[20] == 0x2F) {
    const uint64_t bits = Unsigned(&b[21], 4, false);
    return ImageHeader{"WebP", (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1};
  }
  if (chunk == "VP8X")
    return ImageHeader{"WebP", Unsigned(&b[24], 3, false) + 1, Unsigned(&b[27], 3, false) + 1};
  return s.Corrupt("WebP without a VP8, VP8L or VP8X header first");
}

// The format told by the first bytes, then its header.
Result<ImageHeader> ParseHeader(const Source& s) {
  uint8_t first[12] = {};
  HR_ASSIGN_OR_RETURN(const size_t n, s.read(0, sizeof first, first));
  const std::string_view start(reinterpret_cast<const char*>(first), n);
  const auto starts = [&start](std::string_view magic) {
    return start.substr(0, magic.size()) == magic;
  };
  Result<ImageHeader> header =
      s.Corrupt("not an image format this project reads (PNG, JPEG, TIFF, BMP, PNM or WebP)");
  if (starts("\x89PNG\r\n\x1a\n"sv)) {
    header = PngHeader(s);
  } else if (starts("\xFF\xD8\xFF"sv)) {
    header = JpegHeader(s);
  } else if (starts("II*\0"sv) || starts("MM\0*"sv) || starts("II+\0"sv) || starts("MM\0+"sv)) {
    header = TiffHeader(s);
  } else if (starts("BM"sv)) {
    header = BmpHeader(s);
  } else if (n >= 3 && first[0] == 'P' && first[1] != '\0' &&
             std::strchr("123456Ff", first[1]) != nullptr && std::isspace(first[2])) {
    header = PnmHeader(s);
  } else if (n == sizeof first && starts("RIFF"sv) && start.substr(8) == "WEBP"sv) {
    header = WebpHeader(s);
  }
  if (header.ok() && (header->width_px == 0 || header->height_px == 0)) {
    return s.Corrupt(header->format + " header claims " + std::to_string(header->width_px) + " x " +
                     std::to_string(header->height_px) + " px");
  }
  return header;
}

}  // namespace

Status WriteImageAtomic(const std::string& path, const cv::Mat& image,
                        const std::vector<int>& params) {
  const std::string ext = FileExtension(path);
  if (ext.empty()) return Internal(path + ": no extension to choose the image format by");
  std::vector<uint8_t> bytes;
  bool encoded = false;
  try {
    encoded = !image.empty() && cv::imencode("." + ext, image, bytes, params);
  } catch (const cv::Exception& e) {
    return Internal(path + ": cannot encode the image as ." + ext + " (" + e.what() + ")");
  }
  if (!encoded) return Internal(path + ": cannot encode the image as ." + ext);
  return WriteFileAtomic(path, bytes.data(), bytes.size());
}

Result<ImageHeader> ParseImageHeader(const uint8_t* bytes, size_t size, const std::string& name) {
  const ByteSource memory = [bytes, size](uint64_t offset, size_t n,
                                          uint8_t* out) -> Result<size_t> {
    if (offset >= size || n == 0) return size_t{0};
    const size_t got = static_cast<size_t>(std::min<uint64_t>(n, size - offset));
    std::memcpy(out, bytes + offset, got);
    return got;
  };
  return ParseHeader(Source{memory, name});
}

Result<ImageHeader> ReadImageHeader(const std::string& path) {
  HR_ASSIGN_OR_RETURN(const int opened, OpenRegularFileForRead(path, kMaxImageFileBytes));
  const ScopedFd closed_on_return(opened);
  const ByteSource file = [fd = opened, &path](uint64_t offset, size_t n,
                                               uint8_t* out) -> Result<size_t> {
    if (offset >= kMaxImageFileBytes) return size_t{0};
    size_t got = 0;
    while (got < n) {
      const ssize_t r = ::pread(fd, out + got, n - got, static_cast<off_t>(offset + got));
      if (r < 0 && errno == EINTR) continue;
      if (r < 0) return IoErrorFromErrno(path + ": read failed", errno);
      if (r == 0) break;
      got += static_cast<size_t>(r);
    }
    return got;
  };
  return ParseHeader(Source{file, path});
}

Status CheckImageSize(const ImageHeader& header, const std::string& name, uint64_t max_pixels) {
  if (header.height_px == 0 || header.width_px <= max_pixels / header.height_px)
    return Status::Ok();
  return OutOfRange(name + ": its " + header.format + " header claims " +
                    std::to_string(header.width_px) + " x " + std::to_string(header.height_px) +
                    " px, more than the " + std::to_string(max_pixels) + " px (" +
                    std::to_string(max_pixels / 1'000'000) +
                    " megapixels) an image read here may have");
}

Status CheckImageFile(const std::string& path, uint64_t max_pixels) {
  HR_ASSIGN_OR_RETURN(const ImageHeader header, ReadImageHeader(path));
  return CheckImageSize(header, path, max_pixels);
}

Result<cv::Mat> ReadImageFile(const std::string& path, int flags, uint64_t max_pixels) {
  Result<std::vector<uint8_t>> bytes = ReadFileBytes(path, kMaxImageFileBytes);
  if (bytes.status().code() == StatusCode::kNotFound) return NotFound(path + " is missing");
  HR_RETURN_IF_ERROR(bytes.status());
  HR_ASSIGN_OR_RETURN(const ImageHeader header,
                      ParseImageHeader(bytes->data(), bytes->size(), path));
  HR_RETURN_IF_ERROR(CheckImageSize(header, path, max_pixels));
  cv::Mat image;
  try {
    image = cv::imdecode(*bytes, flags);
  } catch (const std::exception& e) {  // cv::Exception, std::bad_alloc
    return CorruptData(path + ": cannot be decoded (" + e.what() + ")");
  }
  if (image.empty()) return CorruptData(path + ": not a readable image");
  return image;
}

}  // namespace hairrig
