// Views of a ChArUco board held in front of one simulated camera, as a
// technician records them to calibrate that camera's intrinsics alone
//, with the ground truth of every chessboard corner.
//
// The board is ray-cast per pixel through the inverse of the camera's lens
// model and its pattern edges are integrated with stratified samples, as the
// scene renderer does for the AprilTag box (sim_hw/renderer.h), so corners
// land where the camera model projects them. Board frame as in
// core/charuco_board.h; millimetres, pixels in the OpenCV convention.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/charuco_board.h"
#include "core/status.h"
#include "core/transform.h"
#include "sim_hw/scene.h"

namespace hairrig {

struct ChArUcoView {
  cv::Mat image;  // CV_8UC3, BGR
  Rigid3d cam_from_board;
  std::vector<Eigen::Vector2d> corners_px;  // projection of every chessboard corner, by ChArUco id
  std::vector<bool> corner_in_image;        // at least 4 px inside the image
};

// `count` poses spread over the image: the board at 0.9-1.5 times the
// distance at which it would fill the image's width, tilted 10-40 degrees
// about a random in-plane axis and rolled up to 25 degrees, with at least 60 %
// of its corners in the image. Reproducible from `seed`.
std::vector<Rigid3d> ChArUcoBoardPoses(const CameraIntrinsics& camera, const ChArUcoBoard& board,
                                       int count, uint64_t seed);

// The view `camera` records of `board` at `cam_from_board` in front of a grey
// wall, exposed at the camera's nominal exposure with its sensor noise
// (reproducible from `noise_seed`; none when !noise). InvalidArgument when the
// board is behind the camera or seen from its back; an error when the lens
// model cannot be inverted over the image.
Result<ChArUcoView> RenderChArUcoView(const SceneCamera& camera, const ChArUcoBoard& board,
                                      const Rigid3d& cam_from_board, bool noise,
                                      uint64_t noise_seed);

struct ChArUcoSetSummary {
  std::string dir;
  std::string ground_truth;  // dir/ground_truth.json
  std::vector<std::string> images;
};

// What a technician records for one camera, written to `dir` (created):
// view_NNN.png for `views` poses of ChArUcoBoardPoses, and ground_truth.json
// (format "hairrig-charuco-truth": the camera's serial and true intrinsics,
// cam_from_board per image) for `hairrig eval intrinsics`. OutOfRange for a
// camera index outside the scene; IoError names the file it cannot write.
Result<ChArUcoSetSummary> WriteChArUcoSet(const Scene& scene, int camera_index,
                                          const ChArUcoBoard& board, int views, uint64_t seed,
                                          const std::string& dir);

// `hairrig sim charuco`: WriteChArUcoSet for several cameras of a scene, each
// into <out_dir>/<serial>/, rendered in parallel.
struct ChArUcoSetsOptions {
  std::string scene_file;  // the scene (sim_hw/scene.h)
  std::string board_file;  // the board (core/charuco_board.h LoadChArUcoBoard)
  std::string out_dir;
  std::vector<std::string> serials;  // the cameras; empty: every camera of the scene
  int views = 25;                    // images per camera, at least 1
  uint64_t seed = 1;                 // board poses and noise; camera c uses seed + c
  int threads = 2;                   // cameras rendered at once, at least 1

  // InvalidArgument naming the field and its range.
  Status Check() const;
};

struct ChArUcoSetsSummary {
  struct Camera {
    std::string serial;
    ChArUcoSetSummary set;
  };
  std::string out_dir;
  std::string board_file;
  std::vector<Camera> cameras;

  // out, board, cameras (each serial, dir, images (a count), ground_truth).
  nlohmann::json ToJson() const;
  // Per camera where its images are and the calibrate-intrinsics command for them.
  std::string BriefReport() const;
};

// Errors: the scene's or the board's (named), a serial that is not a camera
// of the scene, a camera's set that cannot be written (the first, in order).
Result<ChArUcoSetsSummary> WriteChArUcoSets(const ChArUcoSetsOptions& options);

}  // namespace hairrig
