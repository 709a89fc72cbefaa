#include "core/image_file.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/file_util.h"

namespace hairrig {

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

Result<cv::Mat> ReadImageFile(const std::string& path, int flags) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return NotFound(path + " is missing");
  cv::Mat image = cv::imread(path, flags);
  if (image.empty()) return CorruptData(path + ": not a readable image");
  return image;
}

}  // namespace hairrig
