#include "reconstruction/strand_segments.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace hairrig {
namespace {

std::vector<Eigen::Vector3f> NoisyArc(uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.5f);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 40; ++i) {
    const float x = 2.0f * static_cast<float>(i);
    points.emplace_back(x + noise(rng), noise(rng), 0.01f * x * x + noise(rng));
  }
  return points;
}

// Eq. 3 plus the field terms, evaluated directly.
double Energy(const std::vector<Eigen::Vector3f>& p, const std::vector<Eigen::Vector3f>& initial,
              const PolylineSmoothing& o, const std::vector<VertexFieldTerm>& terms) {
  const auto d = [](const Eigen::Vector3f& v) { return v.cast<double>(); };
  double energy = 0;
  for (size_t i = 0; i < p.size(); ++i)
    energy += o.alpha_position * (d(p[i]) - d(initial[i])).squaredNorm();
  for (size_t i = 0; i + 1 < p.size(); ++i) {
    energy += o.alpha_orientation *
              (d(p[i + 1]) - d(p[i]) - (d(initial[i + 1]) - d(initial[i]))).squaredNorm();
  }
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    energy += o.alpha_curvature * (d(p[i - 1]) - 2 * d(p[i]) + d(p[i + 1])).squaredNorm();
  }
  for (const VertexFieldTerm& t : terms) {
    const double r = t.gradient.cast<double>().dot(d(p[t.vertex])) - t.target;
    energy += t.weight * r * r;
  }
  return energy;
}

TEST(StrandSegments, TheSegmentsDoNotDependOnTheThreadCount) {
  // A wavy sheet of oriented points with jittered positions and confidences:
  // many seeds, each covering others, so a batch's later seeds are often
  // covered by its earlier ones.
  std::mt19937 rng(7);
  std::normal_distribution<float> jitter(0.0f, 0.1f);
  std::uniform_real_distribution<float> confidence(0.1f, 1.0f);
  std::vector<OrientedPoint> points;
  for (float a = 0; a <= 30; a += 0.5f) {
    for (float l = 0; l <= 80; l += 0.5f) {
      OrientedPoint p;
      p.position_mm = {a + jitter(rng), l + jitter(rng), 3.0f * std::sin(l / 10.0f)};
      p.direction = Eigen::Vector3f(0, 1, 0.3f * std::cos(l / 10.0f)).normalized();
      p.confidence = confidence(rng);
      points.push_back(p);
    }
  }
  SegmentGrowthOptions one, three;
  one.threads = 1;
  three.threads = 3;
  SegmentGrowthSummary summary_one, summary_three;
  const std::vector<StrandSegment> a = GrowStrandSegments(points, one, &summary_one);
  const std::vector<StrandSegment> b = GrowStrandSegments(points, three, &summary_three);
  ASSERT_GT(a.size(), 10u);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(a[i].points_mm, b[i].points_mm) << "segment " << i;
  EXPECT_EQ(summary_one.seeds_grown, summary_three.seeds_grown);
  EXPECT_EQ(summary_one.segments, summary_three.segments);
  EXPECT_EQ(summary_one.vertices, summary_three.vertices);
  EXPECT_EQ(summary_one.splits, summary_three.splits);
  EXPECT_EQ(summary_one.stops_hole, summary_three.stops_hole);
  EXPECT_EQ(summary_one.stops_turn, summary_three.stops_turn);
  EXPECT_EQ(summary_one.stops_mls, summary_three.stops_mls);
  EXPECT_EQ(summary_one.stops_length, summary_three.stops_length);
  EXPECT_EQ(summary_one.mean_length_mm, summary_three.mean_length_mm);
}

TEST(PolylineSmoothing, Eq3MatchesADenseSolveOfItsNormalEquations) {
  const std::vector<Eigen::Vector3f> points = NoisyArc(3);
  const PolylineSmoothing o;
  const int n = static_cast<int>(points.size());
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, n), b = Eigen::MatrixXd::Zero(n, 3);
  for (int i = 0; i < n; ++i) {
    q(i, i) += o.alpha_position;
    b.row(i) += o.alpha_position * points[i].cast<double>().transpose();
  }
  for (int i = 0; i + 1 < n; ++i) {
    const Eigen::RowVector3d e = (points[i + 1] - points[i]).cast<double>().transpose();
    q(i, i) += o.alpha_orientation, q(i + 1, i + 1) += o.alpha_orientation;
    q(i, i + 1) -= o.alpha_orientation, q(i + 1, i) -= o.alpha_orientation;
    b.row(i + 1) += o.alpha_orientation * e, b.row(i) -= o.alpha_orientation * e;
  }
  for (int i = 1; i + 1 < n; ++i) {
    const int index[3] = {i - 1, i, i + 1};
    const double coefficient[3] = {1, -2, 1};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        q(index[r], index[c]) += o.alpha_curvature * coefficient[r] * coefficient[c];
  }
  const Eigen::MatrixXd dense = q.ldlt().solve(b);
  const std::vector<Eigen::Vector3f> smooth =
      SmoothPolyline(points, o.alpha_position, o.alpha_orientation, o.alpha_curvature);
  for (int i = 0; i < n; ++i)
    EXPECT_LT((smooth[i].cast<double>() - dense.row(i).transpose()).norm(), 1e-4) << i;
}

TEST(PolylineSmoothing, FixedVerticesStayAndFieldTermsAreMinimisedWithEq3) {
  const std::vector<Eigen::Vector3f> points = NoisyArc(5);
  const size_t n = points.size();
  PolylineSmoothing o;
  o.fixed.assign(n, 0);
  o.fixed[0] = o.fixed[1] = o.fixed[n - 1] = 1;
  std::vector<VertexFieldTerm> terms;
  for (int i = 5; i < 30; ++i) terms.push_back({i, Eigen::Vector3f(0.0f, 0.6f, 0.8f), 3.0, 2.0});
  const std::vector<Eigen::Vector3f> smooth = SmoothPolyline(points, o, terms);
  ASSERT_EQ(smooth.size(), n);
  EXPECT_EQ(smooth[0], points[0]);
  EXPECT_EQ(smooth[1], points[1]);
  EXPECT_EQ(smooth[n - 1], points[n - 1]);
  // A minimum: no free coordinate moved either way lowers the energy.
  const double minimum = Energy(smooth, points, o, terms);
  for (size_t i = 2; i + 1 < n; ++i)
    for (int k = 0; k < 3; ++k)
      for (float step : {-0.01f, 0.01f}) {
        std::vector<Eigen::Vector3f> moved = smooth;
        moved[i][k] += step;
        EXPECT_GE(Energy(moved, points, o, terms), minimum - 1e-6)
            << "vertex " << i << " axis " << k;
      }
  // The terms pull their vertices towards the level 3 of the field: closer than the input.
  double before = 0, after = 0;
  for (const VertexFieldTerm& t : terms) {
    before += std::abs(t.gradient.dot(points[t.vertex]) - t.target);
    after += std::abs(t.gradient.dot(smooth[t.vertex]) - t.target);
  }
  EXPECT_LT(after, 0.5 * before);
}

}  // namespace
}  // namespace hairrig
