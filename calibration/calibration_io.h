// A capture's calibration on disk (<capture>/calibration/, docs/design.md sections
// 4-5), written by `hairrig calibrate` and read by later stages:
//
//   calibration.json        the project's own: per camera the intrinsics (and
//                           their standard deviations), per frame cam_from_box,
//                           cam_from_turntable and the RMS, or why it failed
//   opencv/<serial>.yaml    OpenCV FileStorage: camera_matrix, distortion_coefficients
//                           (k1 k2 p1 p2 k3), image_width, image_height
//   colmap/cameras.txt, images.txt, points3D.txt (empty): model OPENCV (FULL_OPENCV
//                           if k3 is not 0), COLMAP's pixel centres (+0.5 px), poses
//                           cam_from_turntable (the frame the hair is fixed in;
//                           cam_from_box in free mode), so COLMAP and OpenMVS
//                           accept the capture
//   box_as_built.yaml       the box as refined with the cameras (core/calib_box.h
//                           format, with standard deviations), when it was refined:
//                           the box to give a later capture's calibration (--box);
//                           a calibration that does not refine removes an earlier
//                           one's, unless it is the box it was given
//
// Frames as in core/transform.h; mm and px.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "calibration/capture_calibration.h"
#include "calibration/charuco_intrinsics.h"

namespace hairrig {

// The frame views are exported in: turntable in turntable mode, else box.
Rigid3d ObjectFromBox(const CaptureCalibration& result);

// Writes every file above under `dir` (created), each atomically. IoError names the file.
Status WriteCalibration(const std::string& dir, const CaptureCalibrationInput& input,
                        const CaptureCalibration& result);

// What calibration.json holds, as later stages and `hairrig eval` read it.
struct StoredCalibration {
  struct Camera {
    std::string name, serial;
    bool solved = false;
    CameraIntrinsics intrinsics;
    CameraIntrinsics initial;  // before the bundle adjustment
    std::string
        intrinsics_source;  // "views": initial is from Zhang's method (intrinsics_from_views.h)
    std::array<double, CameraIntrinsics::kNumParams> intrinsics_stddev{};
  };
  struct Tag {
    int id = -1;
    std::array<Eigen::Vector2d, 4> corners_px;  // as detected (kTagCornerSigns order)
  };
  struct View {
    int view = 0;
    int camera = 0;  // index into cameras
    std::string frame;
    bool solved = false;
    Rigid3d cam_from_box;
    Rigid3d cam_from_box_initial;  // the per-view PnP before the bundle adjustment
    Rigid3d cam_from_object;  // the object frame: turntable in turntable mode, box in free mode
    std::string failure;      // why the view was not solved
    double rms_px = 0;
    ViewUncertainty uncertainty;  // NaN where calibration.json has none
    std::vector<Tag> tags;        // the detections the bundle adjustment used
  };
  std::string mode;
  Rigid3d turntable_from_box;  // turntable mode
  std::vector<Camera> cameras;
  std::vector<View> views;
  double rms_px = 0;
  // calibration.json's "box": the file of the box it was given (as the user
  // named it, relative to the folder the calibration ran in) and whether it
  // refined that box (then calibration/box_as_built.yaml holds the result).
  std::string box_file;
  bool box_refined = false;
};

// CorruptData names the file and field for anything missing, mistyped or not finite.
Result<StoredCalibration> ReadCalibration(const std::string& calibration_json);

// One camera's intrinsics from a ChArUco calibration (`hairrig
// calibrate-intrinsics`), as a file `hairrig calibrate --intrinsics` accepts:
// format "hairrig-intrinsics", the camera's serial, the board file, the
// intrinsics with their standard deviations and the per-image results.
// Written atomically; IoError names the file.
Status WriteIntrinsicsFile(const std::string& path, const std::string& serial,
                           const std::string& board, const ChArUcoCalibration& result);

// The used images' chessboard corners as mrcal's corners cache, the input of
// `mrcal-calibrate-cameras --corners-cache`: a vnl table "# filename x y level",
// for each used image one row per corner of the board in id order (the rows of
// the board's inner grid in turn), "x y 0" in px (OpenCV convention) or
// "- - -" for a corner not detected, the filename without its folder.
// Written atomically; IoError names the file.
Status WriteMrcalCorners(const std::string& path, const ChArUcoBoard& board,
                         const ChArUcoCalibration& result);

// Intrinsics to hold fixed in a box calibration, by camera serial.
struct IntrinsicsPrior {
  std::string serial;
  CameraIntrinsics intrinsics;
  std::array<double, CameraIntrinsics::kNumParams> stddev{};
  std::string source;  // the file
};

// The priors a file gives: one from a hairrig-intrinsics file, every solved
// camera from a calibration.json. CorruptData names the file and field.
Result<std::vector<IntrinsicsPrior>> ReadIntrinsicsPriors(const std::string& path);

}  // namespace hairrig
