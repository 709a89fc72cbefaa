// Test helper: a capture folder holding only what `hairrig export` reads: a
// comb of straight strands as reconstruction/strands/strands.ply, and a
// `hairrig simulate`-like output under simulation/head-shake/ (frames that
// sway further each frame, and a summary.json at 10 fps); AddPointsAndTruth
// adds oriented points and a ground truth's strands.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "core/file_util.h"
#include "core/strand_io.h"
#include "reconstruction/point_cloud.h"

namespace hairrig_test {

// `count` vertical strands of `points` points, 10 mm apart on a grid, 2 mm
// between points, hanging from z = 300 mm; each point k moved sway_mm * k in x.
inline hairrig::StrandSet Comb(int count, int points, float sway_mm = 0) {
  hairrig::StrandSet s;
  for (int i = 0; i < count; ++i) {
    for (int k = 0; k < points; ++k)
      s.points_mm.emplace_back(10.0f * static_cast<float>(i % 10) + sway_mm * static_cast<float>(k),
                               10.0f * static_cast<float>(i / 10),
                               300.0f - 2.0f * static_cast<float>(k));
    s.point_counts.push_back(static_cast<uint32_t>(points));
  }
  return s;
}

// <TempDir>/<name> (made afresh) with a comb of 100 strands of 50 points,
// `frames` simulated frames of it and, with `guides`, as many frames of 5
// guides of 10 points in guides/; the folder's path.
inline std::string MakeStrandCapture(const std::string& name, int frames, bool guides = false) {
  namespace fs = std::filesystem;
  const std::string dir = ::testing::TempDir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir + "/reconstruction/strands");
  EXPECT_TRUE(
      hairrig::WriteStrands(dir + "/reconstruction/strands/strands.ply", Comb(100, 50)).ok());
  const std::string simulation = dir + "/simulation/head-shake";
  fs::create_directories(simulation + "/frames");
  if (guides) fs::create_directories(simulation + "/guides");
  for (int f = 0; f < frames; ++f) {
    char file[32];
    std::snprintf(file, sizeof file, "/frame_%04d.hair", f);
    const float sway = 0.1f * static_cast<float>(f);
    EXPECT_TRUE(hairrig::WriteStrands(simulation + "/frames" + file, Comb(100, 50, sway)).ok());
    if (guides) {
      EXPECT_TRUE(hairrig::WriteStrands(simulation + "/guides" + file, Comb(5, 10, sway)).ok());
    }
  }
  EXPECT_TRUE(hairrig::WriteFileAtomic(simulation + "/summary.json", R"({"fps": 10})").ok());
  return dir;
}

// Writes <dir>/reconstruction/points.ply (`points` points along x at z = 100
// mm, pointing down), a reconstruction/summary.json naming the turntable
// frame, and <dir>/ground_truth/ground_truth_strands.ply (a comb of 50
// strands of 20 points).
inline void AddPointsAndTruth(const std::string& dir, int points) {
  std::filesystem::create_directories(dir + "/ground_truth");
  EXPECT_TRUE(
      hairrig::WriteStrands(dir + "/ground_truth/ground_truth_strands.ply", Comb(50, 20)).ok());
  std::vector<hairrig::OrientedPoint> cloud(static_cast<size_t>(points));
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].position_mm = Eigen::Vector3f(static_cast<float>(i), 0, 100);
    cloud[i].direction = Eigen::Vector3f(0, 0, -1);
    cloud[i].confidence = 1;
  }
  EXPECT_TRUE(hairrig::WritePointCloudPly(dir + "/reconstruction/points.ply", cloud).ok());
  EXPECT_TRUE(hairrig::WriteFileAtomic(dir + "/reconstruction/summary.json",
                                       R"({"object_frame": "turntable"})")
                  .ok());
}

}  // namespace hairrig_test
