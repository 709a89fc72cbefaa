#include "sim_hw/ground_truth.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/head_json.h"

namespace hairrig {

int NumViews(const Scene& scene) {
  return scene.turntable_stops * static_cast<int>(scene.cameras.size());
}

ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view) {
  const int cams = static_cast<int>(scene.cameras.size());
  return MakeViewGroundTruth(scene, view, view / cams, view % cams,
                             scene.StopAngleDeg(view / cams));
}

ViewGroundTruth MakeViewGroundTruth(const Scene& scene, int view, int stop, int camera_index,
                                    double turntable_deg) {
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

std::string TruthHeadMeshName(const HeadSpec& head) {
  if (head.mesh_file.empty()) return "";
  return FileExtension(head.mesh_file) == "obj" ? "head_mesh.obj" : "head_mesh.ply";
}

Status WriteTruthHeadMesh(const Scene& scene, const std::string& truth_dir,
                          const FileWriter& write) {
  const std::string name = TruthHeadMeshName(scene.head);
  if (name.empty()) return Status::Ok();
  HR_ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(scene.head.mesh_file));
  return WriteFileWith(write, truth_dir + "/" + name, bytes.data(), bytes.size());
}

std::string GroundTruthJson(const Scene& scene, const std::vector<ViewGroundTruth>& views,
                            bool with_maps) {
  nlohmann::json root;
  root["simulation_only"] = true;
  root["note"] =
      "Ground truth of the simulated rig. a_from_b maps frame b to frame a; mm, deg; "
      "pixel (0,0) is the centre of the top-left pixel.";
  root["scene"] = scene.path;
  root["turntable_from_box"] = PoseToJson(scene.turntable_from_box);
  root["head"] = HeadSpecToJson(scene.head, TruthHeadMeshName(scene.head));
  if (with_maps) {
    root["maps"] = {
        {"version", kTruthMapsVersion},
        {"folder", "views"},
        {"files",
         {{"label",
           "NNN_label.png: 8-bit, 0 backdrop, 1 box, 2 head, 3 hair (hair coverage >= 0.5)"},
          {"alpha", "NNN_alpha.png: 16-bit, hair coverage x 65535"},
          {"orientation",
           "NNN_orientation.png: 16-bit, 2D direction of the front-most strand in deg x 100, "
           "[0, 180) from +x towards +y (down); 65535 where no strand"},
          {"depth",
           "NNN_depth.png: 16-bit, depth of the front-most surface along the optical axis, mm x "
           "20; "
           "0 on the backdrop"},
          {"strand",
           "NNN_strand.png: 16-bit, index of the front-most strand in ground_truth_strands.ply + "
           "1; "
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
      v["tags"].push_back({{"id", t.id},
                           {"corners_px", corners},
                           {"facing_deg", t.facing_deg},
                           {"unoccluded", t.unoccluded}});
    }
    root["views"].push_back(v);
  }
  return root.dump(1);
}

}  // namespace hairrig
