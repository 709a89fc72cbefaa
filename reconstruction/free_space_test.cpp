#include "reconstruction/free_space.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/support/front_views_testing.h"

namespace hairrig {
namespace {

TEST(FreeSpace, InFrontOfTheSeenFaceIsFreeBehindItAndBesideItIsNot) {
  const std::vector<ReconstructionView> views = front_views::Cameras(4, 150);
  FreeSpaceOptions four;
  four.min_views = 4;
  const FreeSpace free(views, front_views::FrontFace(24, 24, 100, 200, 4), four);
  // Every view sees the face 10 mm behind a point in front of it.
  EXPECT_EQ(free.ViewsSeeingPast({0, 34, 150}), 4);
  EXPECT_TRUE(free.Free({0, 34, 150}));
  EXPECT_TRUE(free.Free({-15, 28.5, 120}));
  // Within the margin (3 mm) of the face, on it and behind it: hair may be there.
  EXPECT_EQ(free.ViewsSeeingPast({0, 26, 150}), 0);
  EXPECT_FALSE(free.Free({0, 24, 150}));
  EXPECT_FALSE(free.Free({0, 0, 150}));
  // Where no view saw a point (above the face), nothing is known to be empty.
  EXPECT_EQ(free.ViewsSeeingPast({0, 34, 260}), 0);
  // Behind the cameras.
  EXPECT_EQ(free.ViewsSeeingPast({0, 700, 150}), 0);
}

TEST(FreeSpace, KeepsTheNearestSeenDepthNotTheLastOne) {
  // A face at y = 24 and, after it in the list, points the stereo put 48 mm
  // further from the cameras: what lies between them is not known to be empty.
  const std::vector<ReconstructionView> views = front_views::Cameras(4, 150);
  std::vector<OrientedPoint> points = front_views::FrontFace(24, 24, 100, 200, 4);
  const std::vector<OrientedPoint> behind = front_views::FrontFace(-24, 24, 100, 200, 4);
  points.insert(points.end(), behind.begin(), behind.end());
  FreeSpaceOptions four;
  four.min_views = 4;
  const FreeSpace free(views, points, four);
  EXPECT_EQ(free.ViewsSeeingPast({0, 0, 150}), 0);
  EXPECT_TRUE(free.Free({0, 34, 150}));
}

TEST(FreeSpace, FewerViewsThanAskedForDoNotCarve) {
  const std::vector<ReconstructionView> views = front_views::Cameras(4, 150);
  // The points list only the first two views (and an index past the views, ignored).
  std::vector<OrientedPoint> points = front_views::FrontFace(24, 24, 100, 200, 2);
  for (OrientedPoint& p : points) p.views.push_back(9);
  FreeSpaceOptions options;
  options.min_views = 4;
  const FreeSpace four(views, points, options);
  EXPECT_EQ(four.ViewsSeeingPast({0, 34, 150}), 2);
  EXPECT_FALSE(four.Free({0, 34, 150}));
  options.min_views = 2;
  EXPECT_TRUE(FreeSpace(views, points, options).Free({0, 34, 150}));
  // A wider margin than the point stands off: not free.
  options.margin_mm = 12;
  EXPECT_FALSE(FreeSpace(views, points, options).Free({0, 34, 150}));
}

TEST(FreeSpaceOptions, CheckNamesTheBadField) {
  FreeSpaceOptions o;
  EXPECT_TRUE(o.Check().ok());
  o.margin_mm = -1;
  EXPECT_NE(o.Check().message().find("margin_mm"), std::string::npos);
  o = FreeSpaceOptions{};
  o.min_views = 0;
  EXPECT_NE(o.Check().message().find("min_views"), std::string::npos);
  o = FreeSpaceOptions{};
  o.cell_px = 0;
  EXPECT_NE(o.Check().message().find("cell_px"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
