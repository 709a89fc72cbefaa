#include "core/charuco_board.h"

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/aruco/charuco.hpp>
#include <utility>

#include "core/config.h"

namespace hairrig {
namespace {

const std::vector<std::pair<const char*, cv::aruco::PREDEFINED_DICTIONARY_NAME>>& Dictionaries() {
  static const std::vector<std::pair<const char*, cv::aruco::PREDEFINED_DICTIONARY_NAME>> names = {
      {"DICT_4X4_50", cv::aruco::DICT_4X4_50},   {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
      {"DICT_4X4_250", cv::aruco::DICT_4X4_250}, {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
      {"DICT_5X5_50", cv::aruco::DICT_5X5_50},   {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
      {"DICT_5X5_250", cv::aruco::DICT_5X5_250}, {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
      {"DICT_6X6_50", cv::aruco::DICT_6X6_50},   {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
      {"DICT_6X6_250", cv::aruco::DICT_6X6_250}, {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
      {"DICT_7X7_50", cv::aruco::DICT_7X7_50},   {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
      {"DICT_7X7_250", cv::aruco::DICT_7X7_250}, {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
  };
  return names;
}

Eigen::Vector3d ToEigen(const cv::Point3f& p) { return {p.x, p.y, p.z}; }

ChArUcoMarker MakeMarker(const cv::aruco::Dictionary& dictionary, int id,
                         const std::vector<cv::Point3f>& corners) {
  ChArUcoMarker m;
  m.id = id;
  for (int k = 0; k < 4; ++k)
    m.corners_board_mm[static_cast<size_t>(k)] = ToEigen(corners[static_cast<size_t>(k)]);
  const int bits = dictionary.markerSize;
  m.cells = bits + 2;
  m.white.assign(static_cast<size_t>(m.cells * m.cells), false);
  const cv::Mat code =
      cv::aruco::Dictionary::getBitsFromByteList(dictionary.bytesList.rowRange(id, id + 1), bits);
  for (int r = 0; r < bits; ++r)
    for (int c = 0; c < bits; ++c)
      m.white[static_cast<size_t>((r + 1) * m.cells + c + 1)] = code.at<uint8_t>(r, c) != 0;
  return m;
}

}  // namespace

bool ChArUcoBoard::IsWhite(double x_mm, double y_mm) const {
  const Eigen::Vector2d size = size_mm();
  if (!(x_mm >= 0 && y_mm >= 0 && x_mm < size.x() && y_mm < size.y()))
    return true;  // the margin (or NaN)
  const int sx = static_cast<int>(std::floor(x_mm / square_mm));
  const int sy = static_cast<int>(std::floor(y_mm / square_mm));
  if (sx < 0 || sy < 0 || sx >= squares_x || sy >= squares_y) return true;  // the print's margin
  const int index = marker_of_square[static_cast<size_t>(sy * squares_x + sx)];
  if (index < 0) return false;  // a square without a marker is black
  const ChArUcoMarker& m = markers[static_cast<size_t>(index)];
  const Eigen::Vector3d p(x_mm, y_mm, 0);
  const Eigen::Vector3d right = m.corners_board_mm[1] - m.corners_board_mm[0];
  const Eigen::Vector3d down = m.corners_board_mm[3] - m.corners_board_mm[0];
  const double u = (p - m.corners_board_mm[0]).dot(right) / right.squaredNorm();
  const double v = (p - m.corners_board_mm[0]).dot(down) / down.squaredNorm();
  if (u < 0 || v < 0 || u >= 1 || v >= 1) return true;  // white square around its marker
  const int col = static_cast<int>(u * m.cells), row = static_cast<int>(v * m.cells);
  return m.white[static_cast<size_t>(row * m.cells + col)];
}

Result<ChArUcoBoard> MakeChArUcoBoard(const std::string& dictionary, int squares_x, int squares_y,
                                      double square_mm, double marker_mm) {
  if (squares_x < 3 || squares_y < 3)
    return InvalidArgument("squares: a ChArUco board needs at least 3 x 3 squares (got " +
                           std::to_string(squares_x) + " x " + std::to_string(squares_y) + ")");
  if (!(square_mm > 0) || !std::isfinite(square_mm))
    return InvalidArgument("square_mm must be a positive length");
  if (!(marker_mm > 0) || !(marker_mm < square_mm))
    return InvalidArgument("marker_mm must be positive and smaller than square_mm (" +
                           std::to_string(square_mm) + ")");
  const cv::aruco::PREDEFINED_DICTIONARY_NAME* name = nullptr;
  std::string known;
  for (const auto& [text, value] : Dictionaries()) {
    if (dictionary == text) name = &value;
    known += (known.empty() ? "" : ", ") + std::string(text);
  }
  if (name == nullptr)
    return InvalidArgument("dictionary " + QuotedExcerpt(dictionary) + " is not one of " + known);
  const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(*name);
  const int needed = squares_x * squares_y / 2;
  if (dict->bytesList.rows < needed)
    return InvalidArgument("dictionary " + dictionary + " has " +
                           std::to_string(dict->bytesList.rows) + " markers; a " +
                           std::to_string(squares_x) + " x " + std::to_string(squares_y) +
                           " board needs " + std::to_string(needed));
  const cv::Ptr<cv::aruco::CharucoBoard> cv_board = cv::aruco::CharucoBoard::create(
      squares_x, squares_y, static_cast<float>(square_mm), static_cast<float>(marker_mm), dict);
  ChArUcoBoard board;
  board.dictionary = dictionary;
  board.opencv_dictionary = static_cast<int>(*name);
  board.squares_x = squares_x;
  board.squares_y = squares_y;
  board.square_mm = square_mm;
  board.marker_mm = marker_mm;
  for (const cv::Point3f& p : cv_board->chessboardCorners)
    board.corners_board_mm.push_back(ToEigen(p));
  for (size_t i = 0; i < cv_board->ids.size(); ++i)
    board.markers.push_back(MakeMarker(*dict, cv_board->ids[i], cv_board->objPoints[i]));
  board.marker_of_square.assign(static_cast<size_t>(squares_x * squares_y), -1);
  for (size_t i = 0; i < board.markers.size(); ++i) {
    const Eigen::Vector3d centre =
        0.5 * (board.markers[i].corners_board_mm[0] + board.markers[i].corners_board_mm[2]);
    const int sx = static_cast<int>(std::floor(centre.x() / square_mm));
    const int sy = static_cast<int>(std::floor(centre.y() / square_mm));
    board.marker_of_square[static_cast<size_t>(sy * squares_x + sx)] = static_cast<int>(i);
  }
  // A camera (x right, y down, z forward) sees a marker unmirrored when
  // right x down points away from it.
  const ChArUcoMarker& m = board.markers.front();
  const Eigen::Vector3d away = (m.corners_board_mm[1] - m.corners_board_mm[0])
                                   .cross(m.corners_board_mm[3] - m.corners_board_mm[0]);
  board.front_normal_board = -away.normalized();
  return board;
}

Result<ChArUcoBoard> LoadChArUcoBoard(const std::string& path) {
  HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile(path));
  root.AllowOnlyKeys({"dictionary", "squares", "square_mm", "marker_mm"});
  const std::string dictionary = root.String("dictionary", "DICT_5X5_100");
  const std::vector<double> squares = root.Numbers("squares", 2, {.min = 2, .max = 1000});
  const double square_mm = root.Number("square_mm", NumberRange{1e-3, 1e4});
  const double marker_mm = root.Number("marker_mm", NumberRange{1e-3, 1e4});
  HR_RETURN_IF_ERROR(root.status());
  auto board = MakeChArUcoBoard(dictionary, static_cast<int>(squares[0]),
                                static_cast<int>(squares[1]), square_mm, marker_mm);
  if (!board.ok()) return InvalidArgument(path + ": " + board.status().message());
  return board;
}

}  // namespace hairrig
