// Images written to disk the one way every module does it: encoded by the
// file's extension (png, jpg, ...), the encoding checked, the bytes written
// atomically (core/file_util.h), so no reader ever sees half an image; and
// read back with errors that say which file and what is wrong.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// `params`: OpenCV's imwrite flags (e.g. {cv::IMWRITE_JPEG_QUALITY, 85}).
// Internal when the image cannot be encoded in that format (a float image as
// JPEG, an unknown extension); IoError naming the file when it cannot be written.
Status WriteImageAtomic(const std::string& path, const cv::Mat& image,
                        const std::vector<int>& params = {});

// cv::imread with `flags` (cv::IMREAD_UNCHANGED, ...). NotFound naming the
// path when there is no such file; CorruptData when it cannot be decoded.
Result<cv::Mat> ReadImageFile(const std::string& path, int flags);

}  // namespace hairrig
