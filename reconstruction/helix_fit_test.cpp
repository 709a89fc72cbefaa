#include "reconstruction/helix_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace hairrig {
namespace {

// `length_mm` of a helix about the z axis (radius r, pitch P, handedness h)
// from arc length `from_mm`, a point every mm.
std::vector<Eigen::Vector3f> HelixArc(double r, double pitch, int h, double phase, double from_mm,
                                      double length_mm) {
  const double c = pitch / (2 * M_PI), l = std::hypot(r, c);
  std::vector<Eigen::Vector3f> points;
  for (double s = from_mm; s <= from_mm + length_mm; s += 1.0) {
    const double angle = phase + h * s / l;
    points.push_back(Eigen::Vector3d(10 + r * std::cos(angle), -5 + r * std::sin(angle), -c * s / l)
                         .cast<float>());
  }
  return points;
}

TEST(FitHelix, FindsAnExactHelix) {
  for (const int h : {1, -1}) {
    HelixShape shape;
    ASSERT_TRUE(FitHelix(HelixArc(6, 20, h, 0.4, 0, 20), &shape)) << "handedness " << h;
    EXPECT_NEAR(shape.radius_mm, 6, 0.01) << "handedness " << h;
    EXPECT_NEAR(shape.pitch_mm, 20, 0.05) << "handedness " << h;
  }
}

TEST(FitHelix, FindsTheHelixOfNoisyArcs) {
  // Arcs of 20 mm (a third of a turn to half a turn) on helices of several
  // shapes, either handedness, their points off by 0.2 mm (Gaussian per
  // axis, 1 mm apart): of 40 arcs at least 32 are fitted, their median
  // radius within 10 % and their quartiles within 25 % of the truth, the
  // median pitch within 20 %. Measured: radii 6.15, 4.27 and 9.73 mm, pitch 21 for 25.
  std::mt19937 random(7);
  std::normal_distribution<float> noise(0.0f, 0.2f);
  for (const auto& [r, pitch] :
       {std::pair{6.0, 20.0}, std::pair{4.0, 30.0}, std::pair{9.0, 25.0}}) {
    std::vector<double> radii, pitches;
    for (int k = 0; k < 40; ++k) {
      std::vector<Eigen::Vector3f> arc = HelixArc(r, pitch, k % 2 ? 1 : -1, 0.37 * k, 2.0 * k, 20);
      for (Eigen::Vector3f& p : arc)
        p += Eigen::Vector3f(noise(random), noise(random), noise(random));
      HelixShape shape;
      if (!FitHelix(arc, &shape)) continue;
      radii.push_back(shape.radius_mm);
      pitches.push_back(shape.pitch_mm);
    }
    ASSERT_GE(radii.size(), 32u) << "radius " << r;
    std::sort(radii.begin(), radii.end());
    std::sort(pitches.begin(), pitches.end());
    const size_t n = radii.size();
    EXPECT_NEAR(radii[n / 2], r, 0.1 * r) << "radius " << r;
    EXPECT_NEAR(radii[n / 4], r, 0.25 * r) << "radius " << r;
    EXPECT_NEAR(radii[3 * n / 4], r, 0.25 * r) << "radius " << r;
    EXPECT_NEAR(pitches[n / 2], pitch, 0.2 * pitch) << "radius " << r;
  }
}

TEST(FitHelix, RefusesWhatNoHelixFixes) {
  HelixShape shape{1, 2};
  std::vector<Eigen::Vector3f> line, short_arc;
  for (float k = 0; k < 20; ++k) line.emplace_back(0.5f * k, 0.2f * k, -k);
  EXPECT_FALSE(FitHelix(line, &shape));
  short_arc = HelixArc(6, 20, 1, 0, 0, 4);
  EXPECT_FALSE(FitHelix(short_arc, &shape));
  EXPECT_EQ(shape.radius_mm, 1);
  EXPECT_EQ(shape.pitch_mm, 2);
}

}  // namespace
}  // namespace hairrig
