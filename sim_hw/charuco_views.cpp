#include "sim_hw/charuco_views.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/parallel.h"
#include "core/string_format.h"
#include "sim_hw/render_support.h"

namespace hairrig {
namespace {

using render_support::HashPixel;
using render_support::kEdgeSamples;
using render_support::RayTable;

constexpr double kWhiteAlbedo = 0.85;
constexpr double kBlackAlbedo = 0.04;
constexpr double kWallAlbedo = 0.30;
constexpr int kWall = -1, kBlack = 0, kWhite = 1;

// What a ray through pixel position (u, v) hits: the wall, or a black or white
// part of the print (the board and a white margin of half a square).
class BoardHitter {
 public:
  BoardHitter(const RayTable& rays, const ChArUcoBoard& board, const Rigid3d& cam_from_board)
      : rays_(rays), board_(board), board_from_cam_(cam_from_board.Inverse()) {
    margin_mm_ = 0.5 * board.square_mm;
  }

  int Class(double u, double v) const {
    const Eigen::Vector3d d = board_from_cam_.rotation * rays_.Ray(u, v);
    const Eigen::Vector3d& o = board_from_cam_.translation;
    if (std::abs(d.z()) < 1e-12) return kWall;
    const double t = -o.z() / d.z();
    if (t <= 0) return kWall;
    const Eigen::Vector3d p = o + t * d;
    const Eigen::Vector2d size = board_.size_mm();
    if (p.x() < -margin_mm_ || p.y() < -margin_mm_ || p.x() > size.x() + margin_mm_ ||
        p.y() > size.y() + margin_mm_)
      return kWall;
    return board_.IsWhite(p.x(), p.y()) ? kWhite : kBlack;
  }

 private:
  const RayTable& rays_;
  const ChArUcoBoard& board_;
  Rigid3d board_from_cam_;
  double margin_mm_ = 0;
};

double Albedo(int surface_class) {
  return surface_class == kWhite   ? kWhiteAlbedo
         : surface_class == kBlack ? kBlackAlbedo
                                   : kWallAlbedo;
}

// Linear radiance of the view (uniform light of irradiance 1): pixels whose
// four corners agree take their centre's albedo, the others the mean of
// kEdgeSamples^2 stratified samples.
cv::Mat3f BoardRadiance(const BoardHitter& hitter, int width, int height) {
  const int gw = width + 1;
  std::vector<int8_t> corner_class(static_cast<size_t>(gw * (height + 1)));
  for (int j = 0; j <= height; ++j)
    for (int i = 0; i <= width; ++i)
      corner_class[static_cast<size_t>(j * gw + i)] =
          static_cast<int8_t>(hitter.Class(i - 0.5, j - 0.5));
  cv::Mat3f radiance(height, width);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int c00 = corner_class[static_cast<size_t>(y * gw + x)];
      const bool uniform = c00 == corner_class[static_cast<size_t>(y * gw + x + 1)] &&
                           c00 == corner_class[static_cast<size_t>((y + 1) * gw + x)] &&
                           c00 == corner_class[static_cast<size_t>((y + 1) * gw + x + 1)];
      double albedo = 0;
      if (uniform) {
        albedo = Albedo(hitter.Class(x, y));
      } else {
        for (int s = 0; s < kEdgeSamples * kEdgeSamples; ++s) {
          const uint32_t h = HashPixel(x, y, static_cast<uint32_t>(s));
          const double ju = ((s % kEdgeSamples) + (h & 0xffff) / 65536.0) / kEdgeSamples - 0.5;
          const double jv = ((s / kEdgeSamples) + (h >> 16) / 65536.0) / kEdgeSamples - 0.5;
          albedo += Albedo(hitter.Class(x + ju, y + jv));
        }
        albedo /= kEdgeSamples * kEdgeSamples;
      }
      const float value = static_cast<float>(albedo);
      radiance(y, x) = cv::Vec3f(value, value, value);
    }
  }
  return radiance;
}

// cam_from_board with the board's front towards the camera and its axes
// along the camera's before `tilt`.
Eigen::Matrix3d FacingRotation(const ChArUcoBoard& board) {
  // The front normal must map to -z (towards a camera looking along +z).
  if (board.front_normal_board.z() < 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

double FractionInImage(const CameraIntrinsics& camera, const ChArUcoBoard& board,
                       const Rigid3d& cam_from_board) {
  int inside = 0;
  for (const Eigen::Vector3d& c : board.corners_board_mm) {
    Eigen::Vector2d uv;
    if (ProjectChecked(camera, cam_from_board * c, &uv) && uv.x() >= 10 && uv.y() >= 10 &&
        uv.x() <= camera.width_px - 11 && uv.y() <= camera.height_px - 11)
      ++inside;
  }
  return static_cast<double>(inside) / static_cast<double>(board.corners_board_mm.size());
}

}  // namespace

std::vector<Rigid3d> ChArUcoBoardPoses(const CameraIntrinsics& camera, const ChArUcoBoard& board,
                                       int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector2d size = board.size_mm();
  const double filling_distance_mm = camera.fx_px * size.x() / camera.width_px;
  const Eigen::Vector3d centre_board(0.5 * size.x(), 0.5 * size.y(), 0);
  const Eigen::Matrix3d facing = FacingRotation(board);
  std::vector<Rigid3d> poses;
  for (int attempt = 0; static_cast<int>(poses.size()) < count && attempt < 1000 * count;
       ++attempt) {
    const double distance = filling_distance_mm * (0.9 + 0.6 * unit(rng));
    const double axis_angle = 2 * kPi * unit(rng);
    const Eigen::Vector3d tilt_axis(std::cos(axis_angle), std::sin(axis_angle), 0);
    const double tilt = DegToRad(10 + 30 * unit(rng));
    const double roll = DegToRad(-25 + 50 * unit(rng));
    const Eigen::Vector2d target_px(camera.width_px * (0.3 + 0.4 * unit(rng)),
                                    camera.height_px * (0.3 + 0.4 * unit(rng)));
    auto ray = UndistortPixel(camera, target_px);
    if (!ray.ok()) continue;
    const Eigen::Vector3d centre_cam =
        distance * Eigen::Vector3d(ray->x(), ray->y(), 1.0).normalized();
    const Eigen::Matrix3d r = Eigen::AngleAxisd(tilt, tilt_axis).toRotationMatrix() *
                              Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                              facing;
    const Rigid3d pose(r, centre_cam - r * centre_board);
    if (FractionInImage(camera, board, pose) >= 0.6) poses.push_back(pose);
  }
  return poses;
}

Result<ChArUcoView> RenderChArUcoView(const SceneCamera& camera, const ChArUcoBoard& board,
                                      const Rigid3d& cam_from_board, bool noise,
                                      uint64_t noise_seed) {
  const Eigen::Vector3d centre_cam =
      cam_from_board * Eigen::Vector3d(0.5 * board.size_mm().x(), 0.5 * board.size_mm().y(), 0);
  if (centre_cam.z() <= 0)
    return InvalidArgument("the ChArUco board is behind camera " + camera.serial);
  const Eigen::Vector3d front_cam = cam_from_board.rotation * board.front_normal_board;
  if (front_cam.dot(-centre_cam) <= 0)
    return InvalidArgument("camera " + camera.serial + " sees the back of the ChArUco board");
  HR_ASSIGN_OR_RETURN(RayTable rays, RayTable::Build(camera.intrinsics));
  const int width = camera.intrinsics.width_px, height = camera.intrinsics.height_px;
  const BoardHitter hitter(rays, board, cam_from_board);
  ChArUcoView view;
  view.image = render_support::ExposeRadiance(BoardRadiance(hitter, width, height), camera, 0, 0,
                                              noise, noise_seed);
  view.cam_from_board = cam_from_board;
  for (const Eigen::Vector3d& c : board.corners_board_mm) {
    Eigen::Vector2d uv(-1, -1);
    const bool in_front = ProjectChecked(camera.intrinsics, cam_from_board * c, &uv);
    view.corners_px.push_back(uv);
    view.corner_in_image.push_back(in_front && uv.x() >= 4 && uv.y() >= 4 && uv.x() <= width - 5 &&
                                   uv.y() <= height - 5);
  }
  return view;
}

Result<ChArUcoSetSummary> WriteChArUcoSet(const Scene& scene, int camera_index,
                                          const ChArUcoBoard& board, int views, uint64_t seed,
                                          const std::string& dir) {
  if (camera_index < 0 || camera_index >= static_cast<int>(scene.cameras.size()))
    return OutOfRange("camera " + std::to_string(camera_index) + " is not in scene " + scene.path);
  const SceneCamera& camera = scene.cameras[static_cast<size_t>(camera_index)];
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return IoError(dir + ": cannot create the folder: " + ec.message());
  ChArUcoSetSummary summary;
  summary.dir = dir;
  nlohmann::json truth{{"format", "hairrig-charuco-truth"},
                       {"version", 1},
                       {"serial", camera.serial},
                       {"intrinsics", IntrinsicsToJson(camera.intrinsics)}};
  truth["images"] = nlohmann::json::array();
  const std::vector<Rigid3d> poses = ChArUcoBoardPoses(camera.intrinsics, board, views, seed);
  for (size_t i = 0; i < poses.size(); ++i) {
    HR_ASSIGN_OR_RETURN(ChArUcoView view,
                        RenderChArUcoView(camera, board, poses[i], true, seed * 1000003ull + i));
    char name[32];
    std::snprintf(name, sizeof(name), "view_%03zu.png", i);
    const std::string path = (std::filesystem::path(dir) / name).string();
    std::vector<uint8_t> png;
    if (!cv::imencode(".png", view.image, png)) return IoError(path + ": PNG encoding failed");
    HR_RETURN_IF_ERROR(WriteFileAtomic(path, png.data(), png.size()));
    summary.images.push_back(path);
    truth["images"].push_back({{"image", name}, {"cam_from_board", PoseToJson(poses[i])}});
  }
  summary.ground_truth = (std::filesystem::path(dir) / "ground_truth.json").string();
  HR_RETURN_IF_ERROR(WriteFileAtomic(summary.ground_truth, truth.dump(1)));
  return summary;
}

namespace {

// The scene indices of the cameras named by serial; every camera for none.
Result<std::vector<int>> SelectCameras(const Scene& scene, const ChArUcoSetsOptions& options) {
  std::vector<int> cameras;
  for (const std::string& serial : options.serials) {
    const int index = scene.FindCamera(serial);
    if (index < 0)
      return NotFound("--camera " + serial + " is not a camera of " + options.scene_file);
    cameras.push_back(index);
  }
  if (cameras.empty())
    for (size_t c = 0; c < scene.cameras.size(); ++c) cameras.push_back(static_cast<int>(c));
  return cameras;
}

}  // namespace

Status ChArUcoSetsOptions::Check() const {
  if (scene_file.empty()) return InvalidArgument("sim charuco: scene_file is required");
  if (board_file.empty()) return InvalidArgument("sim charuco: board_file is required");
  if (out_dir.empty()) return InvalidArgument("sim charuco: out_dir (--out) is required");
  if (views < 1)
    return InvalidArgument("sim charuco: views must be at least 1, got " + std::to_string(views));
  if (threads < 1)
    return InvalidArgument("sim charuco: threads must be at least 1, got " +
                           std::to_string(threads));
  return Status::Ok();
}

nlohmann::json ChArUcoSetsSummary::ToJson() const {
  nlohmann::json out{{"out", out_dir}, {"board", board_file}, {"cameras", nlohmann::json::array()}};
  for (const Camera& c : cameras) {
    out["cameras"].push_back({{"serial", c.serial},
                              {"dir", c.set.dir},
                              {"images", c.set.images.size()},
                              {"ground_truth", c.set.ground_truth}});
  }
  return out;
}

std::string ChArUcoSetsSummary::BriefReport() const {
  std::string text;
  for (const Camera& c : cameras) {
    text += StringPrintf(
        "%s: %d images of the board in %s (ground truth: %s)\n  calibrate: hairrig "
        "calibrate-intrinsics %s --board %s --serial %s\n",
        c.serial.c_str(), static_cast<int>(c.set.images.size()), c.set.dir.c_str(),
        c.set.ground_truth.c_str(), c.set.dir.c_str(), board_file.c_str(), c.serial.c_str());
  }
  return text;
}

Result<ChArUcoSetsSummary> WriteChArUcoSets(const ChArUcoSetsOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const Scene scene, LoadScene(options.scene_file));
  HR_ASSIGN_OR_RETURN(const ChArUcoBoard board, LoadChArUcoBoard(options.board_file));
  HR_ASSIGN_OR_RETURN(const std::vector<int> cameras, SelectCameras(scene, options));
  std::vector<Result<ChArUcoSetSummary>> sets(cameras.size(), Internal("not rendered"));
  ParallelFor(cameras.size(), options.threads, [&] {
    return [&](size_t i) {
      const SceneCamera& camera = scene.cameras[static_cast<size_t>(cameras[i])];
      sets[i] = WriteChArUcoSet(scene, cameras[i], board, options.views,
                                options.seed + static_cast<uint64_t>(cameras[i]),
                                (std::filesystem::path(options.out_dir) / camera.serial).string());
    };
  });
  ChArUcoSetsSummary summary{options.out_dir, options.board_file, {}};
  for (size_t i = 0; i < cameras.size(); ++i) {
    HR_RETURN_IF_ERROR(sets[i].status());
    summary.cameras.push_back({scene.cameras[static_cast<size_t>(cameras[i])].serial, *sets[i]});
  }
  return summary;
}

}  // namespace hairrig
