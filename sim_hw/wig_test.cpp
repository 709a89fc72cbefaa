#include "sim_hw/wig.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace hairrig {
namespace {

// Smallest value of the ellipsoid's implicit function over all points (1 = on the surface).
double MinEllipsoidLevel(const StrandSet& s, const HeadSpec& head) {
  double level = 1e30;
  for (const auto& p : s.points_mm) {
    level = std::min(
        level, (p.cast<double>() - head.center_turntable_mm).cwiseQuotient(head.radii_mm).norm());
  }
  return level;
}

WigOptions StyleOptions(WigStyle style, int num_strands) {
  WigOptions o;
  o.style = style;
  o.num_strands = num_strands;
  return o;
}

TEST(Wig, EveryStyleIsSeededHangsDownAndStaysOutsideTheHead) {
  HeadSpec head;
  for (WigStyle style : {WigStyle::kStraight, WigStyle::kWavy, WigStyle::kCurly}) {
    WigOptions o = StyleOptions(style, 500);
    auto a = GenerateWig(o, head);
    auto b = GenerateWig(o, head);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->points_mm, b->points_mm) << "same seed, same strands";
    EXPECT_EQ(a->num_strands(), 500u);
    EXPECT_TRUE(a->Check().ok());
    EXPECT_GE(MinEllipsoidLevel(*a, head), 1.0 - 1e-4);
    // Tips are below roots on average: the hair falls.
    double drop = 0;
    const auto offsets = a->Offsets();
    for (size_t s = 0; s < a->num_strands(); ++s)
      drop += a->points_mm[offsets[s]].z() - a->points_mm[offsets[s + 1] - 1].z();
    EXPECT_GT(drop / static_cast<double>(a->num_strands()), 50.0);
    const auto lengths = a->StrandLengths();
    for (double l : lengths) EXPECT_GE(l, o.min_length_mm * 0.95) << "strands keep their length";
    o.seed = 99;
    auto c = GenerateWig(o, head);
    EXPECT_NE(a->points_mm, c->points_mm) << "another seed, other strands";
  }
}

TEST(Wig, CurlyStrandsAreLongerThanTheirSpanAndStraightOnesAreNot) {
  HeadSpec head;
  WigOptions o;
  o.num_strands = 200;
  const auto ratio = [&](WigStyle style) {
    o.style = style;
    auto s = GenerateWig(o, head);
    const auto offsets = s->Offsets();
    const auto lengths = s->StrandLengths();
    double sum = 0;
    for (size_t i = 0; i < s->num_strands(); ++i) {
      sum += lengths[i] / (s->points_mm[offsets[i + 1] - 1] - s->points_mm[offsets[i]]).norm();
    }
    return sum / static_cast<double>(s->num_strands());
  };
  const double straight = ratio(WigStyle::kStraight), curly = ratio(WigStyle::kCurly);
  std::printf("path length / root-tip distance: straight %.2f, curly %.2f\n", straight, curly);
  EXPECT_LT(straight, 1.3);
  EXPECT_GT(curly, straight + 0.5);
}

// Lengths are along the fibre, and a curl gets enough points per turn that
// the polyline turns gently (5 mm steps along the centreline made 14 mm
// curls zigzags turning about 130 deg a point).
TEST(Wig, StrandsHaveTheirFibreLengthAndCurlsAreSampledFinely) {
  HeadSpec head;
  for (WigStyle style : {WigStyle::kStraight, WigStyle::kWavy, WigStyle::kCurly}) {
    WigOptions o = StyleOptions(style, 100);
    o.min_length_mm = 380;
    o.max_length_mm = 400;
    auto s = GenerateWig(o, head);
    ASSERT_TRUE(s.ok());
    for (double l : s->StrandLengths()) {
      EXPECT_GE(l, o.min_length_mm - 0.2 * o.segment_mm);
      EXPECT_LE(l, o.max_length_mm + 1e-3);
    }
    if (style != WigStyle::kCurly) continue;
    const auto offsets = s->Offsets();
    std::vector<double> turns_deg;
    for (size_t k = 0; k < s->num_strands(); ++k) {
      for (size_t i = offsets[k] + 2; i < offsets[k + 1]; ++i) {
        const Eigen::Vector3d a =
            (s->points_mm[i - 1] - s->points_mm[i - 2]).cast<double>().normalized();
        const Eigen::Vector3d b =
            (s->points_mm[i] - s->points_mm[i - 1]).cast<double>().normalized();
        turns_deg.push_back(std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180 / M_PI);
      }
    }
    // 360 / 12 = 30 deg a point on a circle, less on a helix; curls pressed
    // against the head turn more at a few points.
    std::nth_element(turns_deg.begin(), turns_deg.begin() + turns_deg.size() * 9 / 10,
                     turns_deg.end());
    EXPECT_LT(turns_deg[turns_deg.size() * 9 / 10], 32)
        << "90th percentile: about 12 points per turn of the curl";
  }
}

// +1 where most of the strand's consecutive edge triples e1, e2, e3 have
// (e1 x e2) . e3 > 0 (a right-handed helix's torsion), -1 where most have it
// negative.
int CurlHandedness(const StrandSet& s, size_t strand) {
  const auto offsets = s.Offsets();
  int sum = 0;
  for (size_t i = offsets[strand] + 3; i < offsets[strand + 1]; ++i) {
    const Eigen::Vector3f e1 = s.points_mm[i - 2] - s.points_mm[i - 3];
    const Eigen::Vector3f e2 = s.points_mm[i - 1] - s.points_mm[i - 2];
    const Eigen::Vector3f e3 = s.points_mm[i] - s.points_mm[i - 1];
    sum += e1.cross(e2).dot(e3) > 0 ? 1 : -1;
  }
  return sum >= 0 ? 1 : -1;
}

TEST(Wig, CurlsWindLeftHandedInTheShareGiven) {
  HeadSpec head;
  WigOptions o = StyleOptions(WigStyle::kCurly, 300);
  for (const double left_share : {0.0, 0.5, 1.0}) {
    o.curl_left_share = left_share;
    const auto s = GenerateWig(o, head);
    ASSERT_TRUE(s.ok());
    double left = 0;
    for (size_t k = 0; k < s->num_strands(); ++k) left += CurlHandedness(*s, k) < 0 ? 1 : 0;
    EXPECT_NEAR(left / static_cast<double>(s->num_strands()), left_share, 0.1)
        << "curl_left_share " << left_share;
  }
}

TEST(Wig, AMissingStrandFileNamesTheField) {
  WigOptions o;
  o.style = WigStyle::kFile;
  o.file = "/nonexistent/wig.hair";
  auto s = GenerateWig(o, HeadSpec{});
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("wig.file"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
