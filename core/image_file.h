// Images written to disk the one way every module does it: encoded by the
// file's extension (png, jpg, ...), the encoding checked, the bytes written
// atomically (core/file_util.h), so no reader ever sees half an image; and
// read back with errors that say which file and what is wrong.
//
// Reading never trusts the file: only a regular file is opened (a FIFO or a
// device is refused at once, core/file_util.h), its header is read without
// decoding (ReadImageHeader) and an image claiming more than `max_pixels`
// (default kMaxImagePixels, 100 megapixels) is refused before OpenCV allocates
// anything; OpenCV's exceptions become a Status naming the file.
//
//   HR_RETURN_IF_ERROR(CheckImageFile(path));  // when listing inputs: cheap, reads the header
//   HR_ASSIGN_OR_RETURN(cv::Mat image, ReadImageFile(path, cv::IMREAD_COLOR));
#pragma once

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// The most pixels (width x height) an image may claim: 100 megapixels, above
// every camera the rig drives (a 100 MP BGR image is 300 MB decoded).
inline constexpr uint64_t kMaxImagePixels = 100'000'000;
// The largest image file read: 1 GiB.
inline constexpr uint64_t kMaxImageFileBytes = uint64_t{1} << 30;

// What an encoded image's header claims, before any decoding.
struct ImageHeader {
  std::string format;  // "PNG", "JPEG", "TIFF", "BMP", "PNM" (PBM/PGM/PPM/PFM) or "WebP"
  uint64_t width_px = 0, height_px = 0;
};

// `params`: OpenCV's imwrite flags (e.g. {cv::IMWRITE_JPEG_QUALITY, 85}).
// Internal when the image cannot be encoded in that format (a float image as
// JPEG, an unknown extension); IoError naming the file when it cannot be written.
Status WriteImageAtomic(const std::string& path, const cv::Mat& image,
                        const std::vector<int>& params = {});

// The header of the encoded image in `bytes` (PNG IHDR, JPEG SOF, TIFF's
// first IFD, BMP, PNM, WebP), told apart by content, not by extension; `name`
// is the file in messages. CorruptData naming it when the format is none of
// these, the header is truncated or claims a zero size.
Result<ImageHeader> ParseImageHeader(const uint8_t* bytes, size_t size, const std::string& name);
// ParseImageHeader on a file, reading only the header's bytes. Only a regular
// file is opened (InvalidArgument for a FIFO, a device, a folder; never
// blocks); NotFound / IoError name the file.
Result<ImageHeader> ReadImageHeader(const std::string& path);
// OutOfRange naming `name` and the claimed size when `header` has more than
// `max_pixels` pixels.
Status CheckImageSize(const ImageHeader& header, const std::string& name,
                      uint64_t max_pixels = kMaxImagePixels);
// ReadImageHeader and CheckImageSize: an input image checked without decoding it.
Status CheckImageFile(const std::string& path, uint64_t max_pixels = kMaxImagePixels);

// The file decoded by cv::imdecode with `flags` (cv::IMREAD_UNCHANGED, ...),
// after the checks of CheckImageFile. NotFound "<path> is missing" when there
// is no such file; InvalidArgument when it is not a regular file; OutOfRange
// when it claims more than `max_pixels` or is larger than kMaxImageFileBytes;
// CorruptData naming the file when it cannot be decoded (OpenCV's exception
// text included).
Result<cv::Mat> ReadImageFile(const std::string& path, int flags,
                              uint64_t max_pixels = kMaxImagePixels);

}  // namespace hairrig
