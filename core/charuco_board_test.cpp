#include "core/charuco_board.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace hairrig {
namespace {

TEST(ChArUcoBoard, LayoutHasEveryCornerAndAMarkerInEveryWhiteSquare) {
  auto board = MakeChArUcoBoard("DICT_5X5_100", 9, 12, 30, 22);
  ASSERT_TRUE(board.ok()) << board.status().ToString();
  EXPECT_EQ(board->corners_board_mm.size(), 8u * 11u);
  EXPECT_EQ(board->markers.size(), 9u * 12u / 2u);
  EXPECT_EQ(board->opencv_dictionary, 5);  // cv::aruco::DICT_5X5_100
  // Inner corners sit on the square grid.
  for (const Eigen::Vector3d& c : board->corners_board_mm) {
    EXPECT_NEAR(std::fmod(c.x(), 30.0), 0.0, 1e-4);
    EXPECT_NEAR(std::fmod(c.y(), 30.0), 0.0, 1e-4);
    EXPECT_EQ(c.z(), 0.0);
  }
  // Every marker is 22 mm, centred in its square, with a black border cell.
  for (const ChArUcoMarker& m : board->markers) {
    EXPECT_NEAR((m.corners_board_mm[1] - m.corners_board_mm[0]).norm(), 22.0, 1e-4);
    const Eigen::Vector3d centre = 0.5 * (m.corners_board_mm[0] + m.corners_board_mm[2]);
    EXPECT_NEAR(std::fmod(centre.x(), 30.0), 15.0, 1e-4);
    EXPECT_EQ(m.cells, 7);
    EXPECT_FALSE(board->IsWhite(centre.x() + 10.5, centre.y()));  // the marker's border
    EXPECT_TRUE(board->IsWhite(centre.x() + 13.5, centre.y()));   // the white square around it
  }
  // The squares without markers are black; the margin outside is white.
  int black_squares = 0;
  for (int sy = 0; sy < 12; ++sy)
    for (int sx = 0; sx < 9; ++sx) black_squares += !board->IsWhite(30 * sx + 1, 30 * sy + 1);
  EXPECT_EQ(black_squares, 9 * 12 / 2);
  EXPECT_TRUE(board->IsWhite(-5, 10));
  EXPECT_DOUBLE_EQ(std::abs(board->front_normal_board.z()), 1.0);
}

TEST(ChArUcoBoard, BadValuesNameTheField) {
  EXPECT_NE(MakeChArUcoBoard("DICT_5X5_100", 9, 12, 30, 30).status().message().find("marker_mm"),
            std::string::npos);
  EXPECT_NE(MakeChArUcoBoard("DICT_5X5_100", 2, 12, 30, 20).status().message().find("3 x 3"),
            std::string::npos);
  const std::string unknown = MakeChArUcoBoard("DICT_9X9", 9, 12, 30, 20).status().message();
  EXPECT_NE(unknown.find("DICT_9X9"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("DICT_6X6_250"), std::string::npos) << unknown;
  const std::string small = MakeChArUcoBoard("DICT_4X4_50", 12, 12, 30, 20).status().message();
  EXPECT_NE(small.find("needs 72"), std::string::npos) << small;

  const std::string path =
      (std::filesystem::temp_directory_path() / "hairrig_bad_board.yaml").string();
  std::ofstream(path)
      << "dictionary: DICT_5X5_100\nsquares: [9, 12]\nsquare_mm: 30\nmarker_mm: .nan\n";
  const Status bad = LoadChArUcoBoard(path).status();
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("marker_mm"), std::string::npos) << bad.message();
  EXPECT_NE(bad.message().find(path), std::string::npos) << bad.message();
  std::filesystem::remove(path);
}

TEST(ChArUcoBoard, TheShippedBoardLoads) {
  auto board = LoadChArUcoBoard("etc/charuco-board.yaml");
  ASSERT_TRUE(board.ok()) << board.status().ToString();
  EXPECT_EQ(board->squares_x, 9);
}

}  // namespace
}  // namespace hairrig
