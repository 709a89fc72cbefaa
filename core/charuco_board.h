// A ChArUco board (a chessboard whose white squares hold ArUco markers), the
// target a technician waves in front of one camera to calibrate its
// intrinsics alone. Loaded from a file such as
// etc/charuco-board.yaml; the layout is OpenCV's (contrib aruco, 4.6), so the
// board that OpenCV detects and the one the simulated rig renders are one.
//
// Board frame (OpenCV's): the board plane is z = 0, x along the squares_x
// edge, y along the squares_y edge, origin at a board corner; millimetres.
// Chessboard corner i is OpenCV's ChArUco corner id i.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct ChArUcoMarker {
  int id = -1;
  // Corners in OpenCV's order: the marker image's top-left, top-right,
  // bottom-right, bottom-left as printed.
  std::array<Eigen::Vector3d, 4> corners_board_mm;
  int cells = 0;            // cells per side, including the one-cell black border
  std::vector<bool> white;  // cells * cells, row 0 at the top as printed
};

struct ChArUcoBoard {
  std::string dictionary = "DICT_5X5_100";  // OpenCV's predefined dictionary name
  int opencv_dictionary = -1;               // its cv::aruco::PREDEFINED_DICTIONARY_NAME value
  int squares_x = 0, squares_y = 0;
  double square_mm = 0, marker_mm = 0;
  std::vector<Eigen::Vector3d> corners_board_mm;  // inner chessboard corners, by ChArUco id
  std::vector<ChArUcoMarker> markers;
  std::vector<int>
      marker_of_square;  // squares_y x squares_x, row-major: index into markers or -1 (black)
  // Unit normal of the printed side, pointing towards a camera that sees the
  // board unmirrored.
  Eigen::Vector3d front_normal_board = Eigen::Vector3d::UnitZ();

  // True where the printed board is white at (x, y) (board frame, mm); the
  // area outside the squares is the white margin of the print.
  bool IsWhite(double x_mm, double y_mm) const;
  Eigen::Vector2d size_mm() const { return {squares_x * square_mm, squares_y * square_mm}; }
};

// InvalidArgument naming the field for: fewer than 3 squares along a side, a
// marker not smaller than its square, an unknown dictionary (the message
// lists the known ones), or a dictionary with fewer markers than the board needs.
Result<ChArUcoBoard> MakeChArUcoBoard(const std::string& dictionary, int squares_x, int squares_y,
                                      double square_mm, double marker_mm);

// The board of a YAML file (keys dictionary, squares: [x, y], square_mm,
// marker_mm); errors name the file, line and field.
Result<ChArUcoBoard> LoadChArUcoBoard(const std::string& path);

}  // namespace hairrig
