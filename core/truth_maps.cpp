#include "core/truth_maps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/head_json.h"
#include "core/json_file.h"
#include "core/sha256.h"

namespace hairrig {

namespace {

std::string MapPath(const std::string& dir, int view, const char* kind) {
  char name[64];
  std::snprintf(name, sizeof(name), "/%03d_%s.png", view, kind);
  return dir + name;
}

Status WritePng(const std::string& path, const cv::Mat& image, const FileWriter& write) {
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", image, png)) return Internal(path + ": PNG encoding failed");
  return WriteFileWith(write, path, png.data(), png.size());
}

Result<cv::Mat> ReadPng(const std::string& path, int type) {
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) return NotFound(path + ": missing or not a PNG");
  if (m.type() != type)
    return CorruptData(path + ": unexpected pixel type (written by another version?)");
  return m;
}

}  // namespace

Status WriteViewTruthMaps(const std::string& dir, int view, const ViewTruthMaps& maps,
                          const FileWriter& write) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return IoError(dir + ": cannot create (" + ec.message() + ")");
  const cv::Size size = maps.label.size();
  cv::Mat alpha(size, CV_16U), orientation(size, CV_16U), depth(size, CV_16U), strand(size, CV_16U);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      alpha.at<uint16_t>(y, x) = static_cast<uint16_t>(
          std::lround(std::clamp(maps.hair_alpha.at<float>(y, x), 0.f, 1.f) * 65535));
      const float angle = maps.orientation_deg.at<float>(y, x);
      orientation.at<uint16_t>(y, x) = std::isfinite(angle)
                                           ? static_cast<uint16_t>(std::lround(angle * 100) % 18000)
                                           : uint16_t{65535};
      const double d = std::round(maps.depth_mm.at<float>(y, x) * kTruthDepthScale);
      if (!(d >= 0 && d <= 65535)) {
        return OutOfRange(MapPath(dir, view, "depth") + ": depth " +
                          std::to_string(maps.depth_mm.at<float>(y, x)) + " mm at pixel (" +
                          std::to_string(x) + ", " + std::to_string(y) + ") does not fit 16 bits");
      }
      depth.at<uint16_t>(y, x) = static_cast<uint16_t>(d);
      const int id = maps.strand_id.at<int>(y, x);
      if (id >= 65535)
        return OutOfRange(MapPath(dir, view, "strand") + ": strand index " + std::to_string(id) +
                          " does not fit 16 bits");
      strand.at<uint16_t>(y, x) = static_cast<uint16_t>(id + 1);
    }
  }
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "label"), maps.label, write));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "alpha"), alpha, write));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "orientation"), orientation, write));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "depth"), depth, write));
  return WritePng(MapPath(dir, view, "strand"), strand, write);
}

Result<ViewTruthMaps> ReadViewTruthMaps(const std::string& dir, int view) {
  ViewTruthMaps m;
  HR_ASSIGN_OR_RETURN(m.label, ReadPng(MapPath(dir, view, "label"), CV_8U));
  HR_ASSIGN_OR_RETURN(cv::Mat alpha, ReadPng(MapPath(dir, view, "alpha"), CV_16U));
  HR_ASSIGN_OR_RETURN(cv::Mat orientation, ReadPng(MapPath(dir, view, "orientation"), CV_16U));
  HR_ASSIGN_OR_RETURN(cv::Mat depth, ReadPng(MapPath(dir, view, "depth"), CV_16U));
  HR_ASSIGN_OR_RETURN(cv::Mat strand, ReadPng(MapPath(dir, view, "strand"), CV_16U));
  alpha.convertTo(m.hair_alpha, CV_32F, 1.0 / 65535);
  depth.convertTo(m.depth_mm, CV_32F, 1.0 / kTruthDepthScale);
  strand.convertTo(m.strand_id, CV_32S, 1.0, -1.0);
  m.orientation_deg = cv::Mat(orientation.size(), CV_32F);
  for (int y = 0; y < orientation.rows; ++y) {
    for (int x = 0; x < orientation.cols; ++x) {
      const uint16_t o = orientation.at<uint16_t>(y, x);
      m.orientation_deg.at<float>(y, x) =
          o == 65535 ? std::numeric_limits<float>::quiet_NaN() : o / 100.0f;
    }
  }
  return m;
}

namespace {

// checksums.json: {"files": {"views/000_label.png": "<sha256>", ...}}.
Result<std::map<std::string, std::string>> ReadTruthChecksums(const std::string& truth_dir) {
  const std::string path = truth_dir + "/" + kTruthChecksumsFile;
  HR_ASSIGN_OR_RETURN(const nlohmann::json root,
                      ReadJsonFile(path,
                                   "the ground truth was not finished; resume the capture "
                                   "(hairrig capture --resume) to write it again"));
  if (!root.is_object() || !root.contains("files") || !root["files"].is_object())
    return CorruptData(path + ": field 'files': expected an object of file names and SHA-256s");
  std::map<std::string, std::string> sums;
  for (const auto& [name, value] : root["files"].items()) {
    if (!value.is_string() || value.get<std::string>().size() != 64)
      return CorruptData(path + ": field 'files." + name + "': expected a SHA-256");
    sums[name] = value.get<std::string>();
  }
  return sums;
}

}  // namespace

Status WriteTruthChecksums(const std::string& truth_dir,
                           const std::map<std::string, std::string>& sha256,
                           const FileWriter& write) {
  nlohmann::json files = nlohmann::json::object();
  for (const auto& [name, sum] : sha256) files[name] = sum;
  const std::string text = nlohmann::json{{"files", files}}.dump(1);
  return WriteFileWith(write, truth_dir + "/" + kTruthChecksumsFile, text.data(), text.size());
}

Result<std::map<std::string, std::string>> HashTruthFolder(const std::string& truth_dir) {
  std::map<std::string, std::string> sums;
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(truth_dir, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const std::string name =
        std::filesystem::path(it->path()).lexically_relative(truth_dir).generic_string();
    if (name == kTruthChecksumsFile) continue;
    HR_ASSIGN_OR_RETURN(sums[name], Sha256OfFile(it->path().string()));
  }
  if (ec) return IoError(truth_dir + ": cannot list (" + ec.message() + ")");
  return sums;
}

Status VerifyTruthFile(const CaptureTruth& truth, const std::string& path) {
  HR_ASSIGN_OR_RETURN(const std::string resolved, ResolveInside(path, truth.dir));
  const std::string name =
      std::filesystem::path(resolved).lexically_relative(truth.dir).generic_string();
  const auto it = truth.sha256.find(name);
  std::error_code ec;
  if (it == truth.sha256.end() && !std::filesystem::exists(resolved, ec))
    return NotFound(path +
                    " is missing: a view's maps are written once the capture stores its "
                    "frame (resume the capture to shoot it)");
  if (it == truth.sha256.end())
    return CorruptData(path + ": not among the files of " + truth.dir + "/" + kTruthChecksumsFile +
                       "; the ground truth was changed after the capture");
  HR_ASSIGN_OR_RETURN(const std::string actual, Sha256OfFile(resolved));
  if (actual != it->second)
    return CorruptData(path + ": its SHA-256 does not match " + truth.dir + "/" +
                       kTruthChecksumsFile + "; the ground truth was changed after the capture");
  return Status::Ok();
}

Result<ViewTruthMaps> ReadVerifiedViewTruthMaps(const CaptureTruth& truth, int view) {
  for (const char* kind : {"label", "alpha", "orientation", "depth", "strand"})
    HR_RETURN_IF_ERROR(VerifyTruthFile(truth, MapPath(truth.views_dir, view, kind)));
  return ReadViewTruthMaps(truth.views_dir, view);
}

Result<CaptureTruth> ReadCaptureTruth(const std::string& capture_dir) {
  const std::string truth_path = (std::filesystem::path(capture_dir) / "ground_truth").string();
  std::error_code ec;
  if (!std::filesystem::exists(truth_path, ec))
    return NotFound(truth_path +
                    " is missing: only captures from the simulated rig have a "
                    "ground truth");
  CaptureTruth truth;
  HR_ASSIGN_OR_RETURN(truth.dir, ResolveInside(truth_path, capture_dir));
  HR_ASSIGN_OR_RETURN(truth.sha256, ReadTruthChecksums(truth.dir));
  const std::string path = truth.dir + "/ground_truth.json";
  HR_RETURN_IF_ERROR(VerifyTruthFile(truth, path));
  HR_ASSIGN_OR_RETURN(nlohmann::json root, ReadJsonFile(path));
  if (!root.is_object() || !root.contains("views") || !root["views"].is_array())
    return CorruptData(path + ": views is not an array");
  HR_ASSIGN_OR_RETURN(truth.turntable_from_box,
                      PoseFromJson(root.value("turntable_from_box", nlohmann::json()),
                                   path + ": turntable_from_box"));
  for (size_t i = 0; i < root["views"].size(); ++i) {
    const nlohmann::json& j = root["views"][i];
    const std::string where = path + ": views[" + std::to_string(i) + "]";
    if (!j.is_object() || !j.contains("view") || !j["view"].is_number_integer())
      return CorruptData(where + ": view is not an integer");
    CaptureTruth::View v;
    const nlohmann::json serial = j.value("camera_serial", nlohmann::json());
    v.camera_serial = serial.is_string() ? serial.get<std::string>() : "";
    HR_ASSIGN_OR_RETURN(v.intrinsics, IntrinsicsFromJson(j.value("intrinsics", nlohmann::json()),
                                                         where + ".intrinsics"));
    HR_ASSIGN_OR_RETURN(v.cam_from_box, PoseFromJson(j.value("cam_from_box", nlohmann::json()),
                                                     where + ".cam_from_box"));
    truth.views[j["view"].get<int>()] = v;
  }
  truth.views_dir = truth.dir + "/views";
  truth.strands_file = truth.dir + "/ground_truth_strands.ply";
  if (root.contains("head")) {
    HR_ASSIGN_OR_RETURN(HeadSpec head, HeadSpecFromJson(root["head"], truth.dir, path + ": head"));
    if (!head.mesh_file.empty() && !std::filesystem::is_regular_file(head.mesh_file, ec))
      return CorruptData(path + ": head.mesh_file " + head.mesh_file + " is missing");
    if (!head.mesh_file.empty()) HR_RETURN_IF_ERROR(VerifyTruthFile(truth, head.mesh_file));
    truth.head = std::move(head);
  }
  return truth;
}

}  // namespace hairrig
