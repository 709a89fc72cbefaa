#include "sim_hw/ground_truth.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/file_util.h"
#include "core/geometry_json.h"

namespace hairrig {

int NumViews(const Scene& scene) { return scene.turntable_stops * static_cast<int>(scene.cameras.size()); }

ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view) {
  const int cams = static_cast<int>(scene.cameras.size());
  return MakeViewGroundTruth(scene, view, view / cams, view % cams, scene.StopAngleDeg(view / cams));
}

ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view, int stop, int camera_index, double turntable_deg) {
  ViewGroundTruth g;
  g.view = view;
  g.stop = stop;
  g.camera_index = camera_index;
  const SceneCamera& cam = scene.cameras[static_cast<size_t>(g.camera_index)];
  g.camera_serial = cam.serial;
  g.turntable_deg = turntable_deg;
  g.intrinsics = cam.intrinsics;
  g.cam_from_world = cam.cam_from_world;
  g.world_from_turntable = WorldFromTurntable(g.turntable_deg);
  g.cam_from_box = cam.cam_from_world * g.world_from_turntable * scene.turntable_from_box;
  return g;
}


std::string GroundTruthJson(const Scene& scene, const std::vector<ViewGroundTruth>& views, bool with_maps) {
  nlohmann::json root;
  root["simulation_only"] = true;
  root["note"] = "Ground truth of the simulated rig. a_from_b maps frame b to frame a; mm, deg; "
                 "pixel (0,0) is the centre of the top-left pixel.";
  root["scene"] = scene.path;
  root["turntable_from_box"] = PoseToJson(scene.turntable_from_box);
  if (with_maps) {
    root["maps"] = {
        {"version", kTruthMapsVersion},
        {"folder", "views"},
        {"files", {{"label", "NNN_label.png: 8-bit, 0 backdrop, 1 box, 2 head, 3 hair (hair coverage >= 0.5)"},
                   {"alpha", "NNN_alpha.png: 16-bit, hair coverage x 65535"},
                   {"orientation", "NNN_orientation.png: 16-bit, 2D direction of the front-most strand in deg x 100, "
                                   "[0, 180) from +x towards +y (down); 65535 where no strand"},
                   {"depth", "NNN_depth.png: 16-bit, depth of the front-most surface along the optical axis, mm x 20; "
                             "0 on the backdrop"},
                   {"strand", "NNN_strand.png: 16-bit, index of the front-most strand in ground_truth_strands.ply + 1; "
                              "0 where none"}}},
        {"depth_scale_per_mm", kTruthDepthScale},
        {"orientation_scale_per_deg", 100}};
  }
  root["views"] = nlohmann::json::array();
  for (const ViewGroundTruth& g : views) {
    nlohmann::json v;
    v["view"] = g.view;
    v["stop"] = g.stop;
    v["camera_serial"] = g.camera_serial;
    v["turntable_deg"] = g.turntable_deg;
    v["intrinsics"] = IntrinsicsToJson(g.intrinsics);
    v["cam_from_world"] = PoseToJson(g.cam_from_world);
    v["world_from_turntable"] = PoseToJson(g.world_from_turntable);
    v["cam_from_box"] = PoseToJson(g.cam_from_box);
    v["tags"] = nlohmann::json::array();
    for (const TagTruth& t : g.tags) {
      if (!t.in_image || t.facing_deg <= 0) continue;
      nlohmann::json corners = nlohmann::json::array();
      for (const auto& c : t.corners_px) corners.push_back({c.x(), c.y()});
      v["tags"].push_back({{"id", t.id}, {"corners_px", corners}, {"facing_deg", t.facing_deg},
                           {"unoccluded", t.unoccluded}});
    }
    root["views"].push_back(v);
  }
  return root.dump(1);
}

namespace {

std::string MapPath(const std::string& dir, int view, const char* kind) {
  char name[64];
  std::snprintf(name, sizeof(name), "/%03d_%s.png", view, kind);
  return dir + name;
}

Status WritePng(const std::string& path, const cv::Mat& image) {
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", image, png)) return Internal(path + ": PNG encoding failed");
  return WriteFileAtomic(path, png.data(), png.size());
}

Result<cv::Mat> ReadPng(const std::string& path, int type) {
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) return NotFound(path + ": missing or not a PNG");
  if (m.type() != type) return CorruptData(path + ": unexpected pixel type (written by another version?)");
  return m;
}

}  // namespace

Status WriteViewTruthMaps(const std::string& dir, int view, const ViewTruthMaps& maps) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return IoError(dir + ": cannot create (" + ec.message() + ")");
  const cv::Size size = maps.label.size();
  cv::Mat alpha(size, CV_16U), orientation(size, CV_16U), depth(size, CV_16U), strand(size, CV_16U);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      alpha.at<uint16_t>(y, x) = static_cast<uint16_t>(std::lround(std::clamp(maps.hair_alpha.at<float>(y, x), 0.f, 1.f) * 65535));
      const float angle = maps.orientation_deg.at<float>(y, x);
      orientation.at<uint16_t>(y, x) =
          std::isfinite(angle) ? static_cast<uint16_t>(std::lround(angle * 100) % 18000) : uint16_t{65535};
      const double d = std::round(maps.depth_mm.at<float>(y, x) * kTruthDepthScale);
      if (!(d >= 0 && d <= 65535)) {
        return OutOfRange(MapPath(dir, view, "depth") + ": depth " + std::to_string(maps.depth_mm.at<float>(y, x)) +
                          " mm at pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") does not fit 16 bits");
      }
      depth.at<uint16_t>(y, x) = static_cast<uint16_t>(d);
      const int id = maps.strand_id.at<int>(y, x);
      if (id >= 65535) return OutOfRange(MapPath(dir, view, "strand") + ": strand index " + std::to_string(id) + " does not fit 16 bits");
      strand.at<uint16_t>(y, x) = static_cast<uint16_t>(id + 1);
    }
  }
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "label"), maps.label));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "alpha"), alpha));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "orientation"), orientation));
  HR_RETURN_IF_ERROR(WritePng(MapPath(dir, view, "depth"), depth));
  return WritePng(MapPath(dir, view, "strand"), strand);
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
      m.orientation_deg.at<float>(y, x) = o == 65535 ? std::numeric_limits<float>::quiet_NaN() : o / 100.0f;
    }
  }
  return m;
}

}  // namespace hairrig
