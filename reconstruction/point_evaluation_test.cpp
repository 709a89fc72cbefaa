// Precision and recall of oriented samples: exact answers on lattices whose
// points are 10 mm apart (so no point can match a neighbour of its copy), and
// the grid against a brute-force search on a dense random set.
#include "reconstruction/point_evaluation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

namespace hairrig {
namespace {

Eigen::Vector3f RandomDirection(std::mt19937& rng) {
  std::normal_distribution<float> normal(0.f, 1.f);
  Eigen::Vector3f d;
  do {
    d = Eigen::Vector3f(normal(rng), normal(rng), normal(rng));
  } while (d.norm() < 1e-3f);
  return d.normalized();
}

// 8 x 8 x 8 points 10 mm apart with random directions.
std::vector<OrientedSample> Lattice() {
  std::mt19937 rng(7);
  std::vector<OrientedSample> samples;
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        const Eigen::Vector3f cell(static_cast<float>(x), static_cast<float>(y),
                                   static_cast<float>(z));
        samples.push_back({10.f * cell - Eigen::Vector3f(35, 35, 35), RandomDirection(rng)});
      }
    }
  }
  return samples;
}

// `d` turned by `angle_deg` about an axis perpendicular to it.
Eigen::Vector3f Turned(const Eigen::Vector3f& d, float angle_deg) {
  const Eigen::Vector3f other =
      std::abs(d.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f axis = d.cross(other).normalized();
  return Eigen::AngleAxisf(angle_deg * std::numbers::pi_v<float> / 180.f, axis) * d;
}

void ExpectScore(const MatchScore& s, double precision, double recall) {
  EXPECT_DOUBLE_EQ(s.precision, precision)
      << s.threshold.distance_mm << " mm, " << s.threshold.angle_deg << " deg";
  EXPECT_DOUBLE_EQ(s.recall, recall)
      << s.threshold.distance_mm << " mm, " << s.threshold.angle_deg << " deg";
}

TEST(PointEvaluation, IdenticalSetsScoreOneAtEveryThreshold) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> coord(0.f, 50.f);
  std::vector<OrientedSample> samples;
  for (int i = 0; i < 2000; ++i)
    samples.push_back({{coord(rng), coord(rng), coord(rng)}, RandomDirection(rng)});
  for (bool directed : {false, true}) {
    const auto scores =
        MatchSamples(samples, samples, DefaultMatchThresholds(), {.directed = directed});
    ASSERT_EQ(scores.size(), 5u);
    for (const MatchScore& s : scores) {
      ExpectScore(s, 1, 1);
      EXPECT_DOUBLE_EQ(s.f1, 1);
      EXPECT_EQ(s.matched_estimate, 2000);
      EXPECT_EQ(s.matched_truth, 2000);
    }
  }
}

TEST(PointEvaluation, AShiftedCopyMatchesOnlyAtLargerDistances) {
  const std::vector<OrientedSample> truth = Lattice();
  std::vector<OrientedSample> shifted = truth;
  for (OrientedSample& s : shifted) s.position_mm += Eigen::Vector3f(1, 2, 2) * 0.5f;  // 1.5 mm
  const auto scores = MatchSamples(shifted, truth, {{1, 10}, {2, 20}, {4, 90}}, {});
  ExpectScore(scores[0], 0, 0);
  EXPECT_DOUBLE_EQ(scores[0].f1, 0);
  ExpectScore(scores[1], 1, 1);
  ExpectScore(scores[2], 1, 1);
}

TEST(PointEvaluation, DirectionsTurnedBy15DegreesFailAt10AndPassAt20) {
  const std::vector<OrientedSample> truth = Lattice();
  std::vector<OrientedSample> turned = truth;
  for (OrientedSample& s : turned) s.direction = Turned(s.direction, 15);
  for (bool directed : {false, true}) {
    const auto scores = MatchSamples(turned, truth, {{1, 10}, {1, 20}}, {.directed = directed});
    ExpectScore(scores[0], 0, 0);
    ExpectScore(scores[1], 1, 1);
  }
}

TEST(PointEvaluation, FlippedDirectionsMatchOnlyWhenTheSignDoesNotCount) {
  const std::vector<OrientedSample> truth = Lattice();
  std::vector<OrientedSample> flipped = truth;
  for (OrientedSample& s : flipped) s.direction = -s.direction;
  for (const MatchScore& s :
       MatchSamples(flipped, truth, DefaultMatchThresholds(), {.directed = false})) {
    ExpectScore(s, 1, 1);
  }
  for (const MatchScore& s :
       MatchSamples(flipped, truth, DefaultMatchThresholds(), {.directed = true})) {
    ExpectScore(s, 0, 0);
  }
}

TEST(PointEvaluation, HalfTheTruthMissingGivesRecallOneHalfAndPrecisionOne) {
  const std::vector<OrientedSample> truth = Lattice();
  std::vector<OrientedSample> half;
  for (size_t i = 0; i < truth.size(); i += 2) half.push_back(truth[i]);
  for (const MatchScore& s : MatchSamples(half, truth, DefaultMatchThresholds(), {})) {
    ExpectScore(s, 1, 0.5);
    EXPECT_NEAR(s.f1, 2.0 / 3.0, 1e-12);
    EXPECT_EQ(s.matched_estimate, 256);
    EXPECT_EQ(s.matched_truth, 256);
  }
}

TEST(PointEvaluation, EmptySetsScoreZero) {
  const std::vector<OrientedSample> truth = Lattice();
  for (const MatchScore& s : MatchSamples({}, truth, DefaultMatchThresholds(), {}))
    ExpectScore(s, 0, 0);
  for (const MatchScore& s : MatchSamples(truth, {}, DefaultMatchThresholds(), {}))
    ExpectScore(s, 0, 0);
}

// The grid's answer, searched by comparing every pair with the same arithmetic.
std::vector<std::pair<int64_t, int64_t>> BruteForce(const std::vector<OrientedSample>& estimate,
                                                    const std::vector<OrientedSample>& truth,
                                                    const std::vector<MatchThreshold>& thresholds,
                                                    bool directed) {
  const auto matched = [&](const std::vector<OrientedSample>& queries,
                           const std::vector<OrientedSample>& targets, const MatchThreshold& t) {
    const auto max_d2 = static_cast<float>(t.distance_mm * t.distance_mm);
    const auto min_cos = static_cast<float>(std::cos(t.angle_deg * std::numbers::pi / 180) - 1e-6);
    int64_t n = 0;
    for (const OrientedSample& q : queries) {
      const Eigen::Vector3f qd = q.direction.normalized();
      n += std::any_of(targets.begin(), targets.end(), [&](const OrientedSample& s) {
        float c = s.direction.normalized().dot(qd);
        if (!directed) c = std::fabs(c);
        return (s.position_mm - q.position_mm).squaredNorm() <= max_d2 && c >= min_cos;
      });
    }
    return n;
  };
  std::vector<std::pair<int64_t, int64_t>> counts;
  for (const MatchThreshold& t : thresholds) {
    counts.emplace_back(matched(estimate, truth, t), matched(truth, estimate, t));
  }
  return counts;
}

TEST(PointEvaluation, TheGridAgreesWithABruteForceSearch) {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<float> coord(0.f, 50.f);
  std::normal_distribution<float> noise(0.f, 1.5f);
  std::vector<OrientedSample> truth, estimate;
  for (int i = 0; i < 2000; ++i) {
    truth.push_back({{coord(rng), coord(rng), coord(rng)}, RandomDirection(rng)});
    if (i % 4 == 3) {
      estimate.push_back(
          {{coord(rng), coord(rng), coord(rng)}, RandomDirection(rng)});  // an outlier
    } else {
      const Eigen::Vector3f d = truth.back().direction + 0.4f * RandomDirection(rng);
      estimate.push_back(
          {truth.back().position_mm + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)),
           (i % 2 ? -3.f : 2.f) * d});  // not unit, some flipped
    }
  }
  std::vector<MatchThreshold> thresholds = DefaultMatchThresholds();
  thresholds.push_back({0.5, 5});
  thresholds.push_back({2.5, 180});
  for (bool directed : {false, true}) {
    const auto expected = BruteForce(estimate, truth, thresholds, directed);
    for (int threads : {1, 2}) {
      const auto scores =
          MatchSamples(estimate, truth, thresholds, {.directed = directed, .threads = threads});
      ASSERT_EQ(scores.size(), thresholds.size());
      for (size_t t = 0; t < thresholds.size(); ++t) {
        EXPECT_EQ(scores[t].matched_estimate, expected[t].first)
            << "threshold " << t << " directed " << directed;
        EXPECT_EQ(scores[t].matched_truth, expected[t].second)
            << "threshold " << t << " directed " << directed;
        EXPECT_DOUBLE_EQ(scores[t].precision, static_cast<double>(expected[t].first) / 2000);
        EXPECT_DOUBLE_EQ(scores[t].recall, static_cast<double>(expected[t].second) / 2000);
      }
      EXPECT_GT(scores[0].matched_estimate, 0);
      EXPECT_LT(scores[4].matched_estimate, 2000);
    }
  }
}

// The nearest estimate sample within a threshold, searched by comparing every
// pair with the grid's arithmetic (ties: the lower index).
std::vector<int64_t> BruteForceNearest(const std::vector<OrientedSample>& estimate,
                                       const std::vector<OrientedSample>& truth,
                                       const MatchThreshold& t, bool directed) {
  const auto max_d2 = static_cast<float>(t.distance_mm * t.distance_mm);
  const auto min_cos = static_cast<float>(std::cos(t.angle_deg * std::numbers::pi / 180) - 1e-6);
  std::vector<int64_t> nearest;
  for (const OrientedSample& q : truth) {
    const Eigen::Vector3f qd = q.direction.normalized();
    int64_t best = -1;
    float best2 = max_d2;
    for (size_t i = 0; i < estimate.size(); ++i) {
      if (!(estimate[i].direction.norm() > 0)) continue;  // matches nothing
      const float d2 = (estimate[i].position_mm - q.position_mm).squaredNorm();
      float c = estimate[i].direction.normalized().dot(qd);
      if (!directed) c = std::fabs(c);
      if (d2 > best2 || c < min_cos) continue;
      if (best < 0 || d2 < best2) {
        best = static_cast<int64_t>(i);
        best2 = d2;
      }
    }
    nearest.push_back(best);
  }
  return nearest;
}

TEST(PointEvaluation, NearestMatchesAgreeWithABruteForceSearchAndWithTheMatchCounts) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> coord(0.f, 40.f);
  std::vector<OrientedSample> truth, estimate;
  for (int i = 0; i < 1500; ++i) {
    truth.push_back({{coord(rng), coord(rng), coord(rng)}, RandomDirection(rng)});
    estimate.push_back(
        {{coord(rng), coord(rng), coord(rng)}, (i % 3 ? 1.f : -2.f) * RandomDirection(rng)});
  }
  estimate.push_back({{1, 1, 1}, Eigen::Vector3f::Zero()});  // no direction: never chosen
  for (const MatchThreshold t :
       {MatchThreshold{3, 30}, MatchThreshold{2.5, 180}, MatchThreshold{2, 90}}) {
    for (bool directed : {false, true}) {
      const std::vector<int64_t> expected = BruteForceNearest(estimate, truth, t, directed);
      for (int threads : {1, 2}) {
        const std::vector<int64_t> nearest =
            NearestMatches(estimate, truth, t, {.directed = directed, .threads = threads});
        ASSERT_EQ(nearest.size(), truth.size());
        EXPECT_EQ(nearest, expected)
            << t.distance_mm << " mm, " << t.angle_deg << " deg, directed " << directed;
      }
      // A true sample has a nearest match exactly when MatchSamples counts it as matched.
      const std::vector<int64_t> nearest =
          NearestMatches(estimate, truth, t, {.directed = directed});
      const int64_t matched =
          std::count_if(nearest.begin(), nearest.end(), [](int64_t i) { return i >= 0; });
      EXPECT_EQ(matched,
                MatchSamples(estimate, truth, {t}, {.directed = directed})[0].matched_truth);
      EXPECT_GT(matched, 0);
      EXPECT_LT(matched, 1500);
    }
  }
}

TEST(PointEvaluation, NearestMatchesPickTheNearerOfTwoAndTheLowerIndexOfEquals) {
  const Eigen::Vector3f x = Eigen::Vector3f::UnitX();
  const std::vector<OrientedSample> truth = {{{0, 0, 0}, x}, {{10, 0, 0}, x}, {{20, 0, 0}, x}};
  const std::vector<OrientedSample> estimate = {
      {{0, 2, 0}, x},
      {{0, 1, 0}, x},  // the second is nearer to truth 0
      {{10, 1, 0}, x},
      {{10, -1, 0}, x},                         // equally near truth 1: the lower index
      {{20, 1, 0}, Eigen::Vector3f::UnitY()}};  // too steep for truth 2
  EXPECT_EQ(NearestMatches(estimate, truth, {3, 30}, {}), (std::vector<int64_t>{1, 2, -1}));
  EXPECT_EQ(NearestMatches({}, truth, {3, 30}, {}), (std::vector<int64_t>{-1, -1, -1}));
  EXPECT_TRUE(NearestMatches(estimate, {}, {3, 30}, {}).empty());
}

TEST(PointEvaluation, SubsetRecallKeepsThePrecisionOfTheWholeTruth) {
  const std::vector<OrientedSample> truth = Lattice();
  std::vector<OrientedSample> half;
  std::vector<uint8_t> in_half(truth.size(), 0), in_other_half(truth.size(), 0);
  for (size_t i = 0; i < truth.size(); ++i) {
    (i % 2 == 0 ? in_half : in_other_half)[i] = 1;
    if (i % 2 == 0) half.push_back(truth[i]);
  }
  for (const auto& [subset, recall] : {std::pair{in_half, 1.0}, std::pair{in_other_half, 0.0}}) {
    const SubsetMatchScores scores =
        MatchSamplesAndSubset(half, truth, subset, DefaultMatchThresholds(), {});
    ASSERT_EQ(scores.subset.size(), 5u);
    EXPECT_EQ(scores.subset_size, 256);
    for (size_t t = 0; t < scores.subset.size(); ++t) {
      ExpectScore(scores.all[t], 1, 0.5);
      ExpectScore(scores.subset[t], 1, recall);
    }
  }
  EXPECT_TRUE(MatchSamplesAndSubset(half, truth, {}, DefaultMatchThresholds(), {}).subset.empty());
}

TEST(PointEvaluation, StrandsAreSampledAtMostAStepApartWithTheirSegmentsDirection) {
  const std::vector<std::vector<Eigen::Vector3f>> strands = {
      {{0, 0, 0}, {2.5f, 0, 0}, {2.5f, 1, 0}}, {{5, 5, 5}}, {{1, 1, 1}, {1, 1, 1}, {1, 1, 2}}};
  const std::vector<OrientedSample> samples = SampleStrands(strands, 1.0);
  // 0, 1/3, 2/3 of the first segment; the second's start; the tip; the third strand's start and
  // tip.
  ASSERT_EQ(samples.size(), 7u);
  EXPECT_NEAR(samples[1].position_mm.x(), 2.5f / 3, 1e-6f);
  EXPECT_EQ(samples[2].direction, Eigen::Vector3f::UnitX());
  EXPECT_EQ(samples[3].position_mm, Eigen::Vector3f(2.5f, 0, 0));
  EXPECT_EQ(samples[3].direction, Eigen::Vector3f::UnitY());
  EXPECT_EQ(samples[4].position_mm, Eigen::Vector3f(2.5f, 1, 0));
  EXPECT_EQ(samples[4].direction, Eigen::Vector3f::UnitY());
  EXPECT_EQ(samples[5].position_mm, Eigen::Vector3f(1, 1, 1));
  EXPECT_EQ(samples[6].direction, Eigen::Vector3f::UnitZ());
  StrandSet set;
  for (const auto& s : strands) set.AddStrand(s);
  const std::vector<OrientedSample> from_set = SampleStrands(set, 1.0);
  ASSERT_EQ(from_set.size(), samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    EXPECT_EQ(from_set[i].position_mm, samples[i].position_mm);
  // The strand each sample comes from (the second strand, of one point, has none).
  std::vector<uint32_t> strand_of{9};
  const std::vector<OrientedSample> indexed = SampleStrands(set, 1.0, &strand_of);
  ASSERT_EQ(indexed.size(), samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    EXPECT_EQ(indexed[i].position_mm, samples[i].position_mm);
  EXPECT_EQ(strand_of, (std::vector<uint32_t>{0, 0, 0, 0, 0, 2, 2}));
}

}  // namespace
}  // namespace hairrig
