#include "reconstruction/point_cloud.h"

#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "core/file_util.h"

namespace hairrig {
namespace {

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "/" + name; }

bool Contains(const Status& s, const std::string& text) {
  return s.message().find(text) != std::string::npos;
}

const char* const kAsciiHeader =
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float "
    "z\n"
    "property float nx\nproperty float ny\nproperty float nz\nend_header\n";

TEST(PointCloudPly, ARoundTripOfRandomPointsIsBitIdentical) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-300.f, 300.f), unit(-1.f, 1.f), confidence(0.f, 1.f);
  std::uniform_int_distribution<int> view_count(0, 6), view(0, 65535);
  std::vector<OrientedPoint> points(1000);
  for (OrientedPoint& p : points) {
    p.position_mm = {coord(rng), coord(rng), coord(rng)};
    p.direction = Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).normalized();
    p.confidence = confidence(rng);
    for (int k = view_count(rng); k > 0; --k) p.views.push_back(static_cast<uint16_t>(view(rng)));
  }
  points[3].position_mm.x() = -0.f;
  const std::string path = TempPath("round_trip.ply");
  for (size_t views : {size_t{0}, size_t{300}}) {  // 300: the list's count no longer fits a uchar
    points[5].views.assign(views, uint16_t{9});
    ASSERT_TRUE(WritePointCloudPly(path, points).ok());
    auto back = ReadPointCloudPly(path);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ASSERT_EQ(back->size(), points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const OrientedPoint &a = points[i], &b = (*back)[i];
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(std::bit_cast<uint32_t>(a.position_mm[k]),
                  std::bit_cast<uint32_t>(b.position_mm[k]))
            << i;
        ASSERT_EQ(std::bit_cast<uint32_t>(a.direction[k]), std::bit_cast<uint32_t>(b.direction[k]))
            << i;
      }
      ASSERT_EQ(std::bit_cast<uint32_t>(a.confidence), std::bit_cast<uint32_t>(b.confidence)) << i;
      ASSERT_EQ(a.views, b.views) << i;
    }
  }
}

TEST(PointCloudPly, AHeaderClaimingATrillionVerticesIsRefusedQuickly) {
  const std::string path = TempPath("trillion.ply");
  std::string text =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float "
      "x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float "
      "confidence\n"
      "property list uchar ushort views\nend_header\n";
  text += std::string(29 * 4, '\0');
  ASSERT_TRUE(WriteFileAtomic(path, text).ok());
  const auto start = std::chrono::steady_clock::now();
  auto points = ReadPointCloudPly(path);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
  ASSERT_FALSE(points.ok());
  EXPECT_EQ(points.status().code(), StatusCode::kCorruptData);
  EXPECT_TRUE(Contains(points.status(), path)) << points.status().message();
}

TEST(PointCloudPly, ANanCoordinateIsRefusedNamingTheVertex) {
  std::vector<OrientedPoint> points(4);
  for (OrientedPoint& p : points) p.direction = Eigen::Vector3f::UnitZ();
  const std::string path = TempPath("nan.ply");
  ASSERT_TRUE(WritePointCloudPly(path, points).ok());
  auto bytes = ReadFileBytes(path);
  ASSERT_TRUE(bytes.ok());
  const std::string text(bytes->begin(), bytes->end());
  const size_t body = text.find("end_header\n") + 11;
  const size_t record = 7 * sizeof(float) + 1;  // no views: a zero count
  const float nan = std::nanf("");
  std::memcpy(bytes->data() + body + 2 * record + sizeof(float), &nan,
              sizeof(float));  // vertex 2's y
  ASSERT_TRUE(WriteFileAtomic(path, bytes->data(), bytes->size()).ok());
  auto back = ReadPointCloudPly(path);
  ASSERT_FALSE(back.ok());
  EXPECT_EQ(back.status().code(), StatusCode::kCorruptData);
  EXPECT_TRUE(Contains(back.status(), path + ": vertex 2 has a non-finite y"))
      << back.status().message();

  points[1].position_mm.z() = std::numeric_limits<float>::infinity();
  const Status refused = WritePointCloudPly(TempPath("inf.ply"), points);
  EXPECT_EQ(refused.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(Contains(refused, "point 1")) << refused.message();
}

TEST(PointCloudPly, AFileWithoutNxIsRefusedNamingTheProperty) {
  const std::string path = TempPath("no_nx.ply");
  ASSERT_TRUE(WriteFileAtomic(
                  path,
                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "property float z\nproperty float ny\nproperty float nz\nend_header\n0 0 0 0 1\n")
                  .ok());
  auto points = ReadPointCloudPly(path);
  ASSERT_FALSE(points.ok());
  EXPECT_EQ(points.status().code(), StatusCode::kCorruptData);
  EXPECT_TRUE(Contains(points.status(), path)) << points.status().message();
  EXPECT_TRUE(Contains(points.status(), "'nx'")) << points.status().message();
}

TEST(PointCloudPly, AnAsciiFileWrittenByHandIsRead) {
  const std::string path = TempPath("by_hand.ply");
  ASSERT_TRUE(
      WriteFileAtomic(
          path,
          "ply\r\nformat ascii 1.0\r\ncomment from another tool\r\n"
          "element camera 1\r\nproperty list uchar float name\r\nproperty int id\r\n"
          "element vertex 2\r\nproperty double nz\r\nproperty float x\r\nproperty uchar red\r\n"
          "property float y\r\nproperty float z\r\nproperty float nx\r\nproperty float ny\r\n"
          "property list int uint views\r\nend_header\r\n"
          "3 1.5 2 3 17\r\n"
          "1 1.25 200 -2 3e2 0 0 2 4 7\r\n"
          "-0.5 0 0 0 0 0.8 0.6 0\r\n")
          .ok());
  auto points = ReadPointCloudPly(path);
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  ASSERT_EQ(points->size(), 2u);
  EXPECT_EQ((*points)[0].position_mm, Eigen::Vector3f(1.25f, -2, 300));
  EXPECT_EQ((*points)[0].direction, Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ((*points)[0].confidence, 1.f)
      << "no confidence property: the points are taken at their word";
  EXPECT_EQ((*points)[0].views, (std::vector<uint16_t>{4, 7}));
  EXPECT_EQ((*points)[1].direction, Eigen::Vector3f(0.8f, 0.6f, -0.5f));
  EXPECT_TRUE((*points)[1].views.empty());

  ASSERT_TRUE(WriteFileAtomic(path, std::string(kAsciiHeader) + "0 0 0 1 0 0\n1 1 1 0 1 0").ok());
  auto minimal = ReadPointCloudPly(path);
  ASSERT_TRUE(minimal.ok()) << minimal.status().ToString() << " (the last line lacks its newline)";
  EXPECT_EQ((*minimal)[1].position_mm, Eigen::Vector3f(1, 1, 1));

  ASSERT_TRUE(WriteFileAtomic(path, std::string(kAsciiHeader) + "0 0 0 1 0 0\n1 1 1 0 1\n").ok());
  EXPECT_EQ(ReadPointCloudPly(path).status().code(), StatusCode::kCorruptData) << "a value short";
}

}  // namespace
}  // namespace hairrig
