#include "calibration/intrinsics_folder.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "calibration/calibration_io.h"
#include "core/charuco_board.h"
#include "core/geometry_json.h"
#include "core/string_format.h"

namespace hairrig {

namespace {

namespace fs = std::filesystem;

bool IsImageFile(const fs::directory_entry& entry) {
  std::string ext = entry.path().extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return entry.is_regular_file() &&
         (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff");
}

// The images directly in `dir`, by name.
Result<std::vector<std::string>> ImagesIn(const std::string& dir) {
  std::vector<std::string> paths;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec))
    if (IsImageFile(entry)) paths.push_back(entry.path().string());
  if (ec) return IoError(dir + ": cannot list the folder (" + ec.message() + ")");
  std::sort(paths.begin(), paths.end());
  if (paths.empty())
    return InvalidArgument(dir +
                           ": no images (.png, .jpg, .tif) of the ChArUco board in this folder");
  return paths;
}

}  // namespace

Status IntrinsicsFolderOptions::Check() const {
  if (images_dir.empty())
    return InvalidArgument("calibrate-intrinsics: images_dir (the image folder) is required");
  if (board_file.empty()) return InvalidArgument("calibrate-intrinsics: board_file is required");
  if (serial.empty())
    return InvalidArgument("calibrate-intrinsics: serial (the camera's serial) is required");
  return calibration.Check().WithContext("calibrate-intrinsics: calibration");
}

nlohmann::json IntrinsicsFolderSummary::ToJson() const {
  nlohmann::json j{{"out", out_file},
                   {"serial", serial},
                   {"images", images},
                   {"images_used", result.images_used},
                   {"rms_px", result.rms_px},
                   {"intrinsics", IntrinsicsToJson(result.intrinsics)},
                   {"left_out", nlohmann::json::array()}};
  for (size_t k = 0; k < result.stddev.size(); ++k)
    j["intrinsics_stddev"][CameraIntrinsics::kParamNames[k]] = result.stddev[k];
  for (const ChArUcoImage& image : result.images)
    if (!image.used) j["left_out"].push_back(image.path + ": " + image.failure);
  return j;
}

std::string IntrinsicsFolderSummary::BriefReport() const {
  std::string text =
      StringPrintf("intrinsics of %s from %d of %d images, RMS %.3f px -> %s\n", serial.c_str(),
                   result.images_used, images, result.rms_px, out_file.c_str());
  const auto k = result.intrinsics.ToParams();
  for (size_t p = 0; p < k.size(); ++p) {  // fx, fy, cx, cy in px, then the distortion coefficients
    text += StringPrintf(p < 4 ? "  %-6s %10.3f +- %.3f\n" : "  %-6s %10.6f +- %.6f\n",
                         CameraIntrinsics::kParamNames[p], k[p], result.stddev[p]);
  }
  for (const ChArUcoImage& image : result.images)
    if (!image.used) text += "  left out: " + image.path + ": " + image.failure + "\n";
  text += "  use it: hairrig calibrate CAPTURE --intrinsics " + out_file +
          " [--intrinsics OTHER_CAMERA.json]\n";
  return text;
}

Result<IntrinsicsFolderSummary> CalibrateIntrinsicsFolder(const IntrinsicsFolderOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const ChArUcoBoard board, LoadChArUcoBoard(options.board_file));
  HR_ASSIGN_OR_RETURN(const std::vector<std::string> images, ImagesIn(options.images_dir));
  IntrinsicsFolderSummary summary;
  summary.serial = options.serial;
  summary.images = static_cast<int>(images.size());
  summary.out_file = options.out_file.empty()
                         ? (fs::path(options.images_dir) / "intrinsics.json").string()
                         : options.out_file;
  HR_ASSIGN_OR_RETURN(summary.result,
                      CalibrateIntrinsicsFromChArUco(images, board, options.calibration));
  HR_RETURN_IF_ERROR(
      WriteIntrinsicsFile(summary.out_file, options.serial, options.board_file, summary.result));
  if (!options.mrcal_corners_file.empty())
    HR_RETURN_IF_ERROR(WriteMrcalCorners(options.mrcal_corners_file, board, summary.result));
  return summary;
}

}  // namespace hairrig
