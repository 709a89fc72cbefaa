// The strand protocol on combs of straight strands whose answers are exact:
// strands 10 mm apart (no sample is within 4 mm of another strand's), points
// 1 mm apart and sampled every 1 mm, so samples of copies coincide.
#include "reconstruction/strand_evaluation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

namespace hairrig {
namespace {

// `count` strands of `points` points 1 mm apart up +z, roots 10 mm apart along x.
StrandSet Comb(int count, int points) {
  StrandSet set;
  for (int i = 0; i < count; ++i) {
    std::vector<Eigen::Vector3f> strand;
    for (int k = 0; k < points; ++k)
      strand.emplace_back(static_cast<float>(10 * i), 0.f, static_cast<float>(k));
    set.AddStrand(strand);
  }
  return set;
}

// Each strand's points [begin, end).
std::vector<std::vector<Eigen::Vector3f>> Strands(const StrandSet& set) {
  std::vector<std::vector<Eigen::Vector3f>> out;
  const std::vector<size_t> offsets = set.Offsets();
  for (size_t s = 0; s < set.num_strands(); ++s)
    out.emplace_back(set.points_mm.begin() + static_cast<std::ptrdiff_t>(offsets[s]),
                     set.points_mm.begin() + static_cast<std::ptrdiff_t>(offsets[s + 1]));
  return out;
}

void ExpectAll(const std::vector<MatchScore>& scores, double precision, double recall,
               const char* what) {
  ASSERT_EQ(scores.size(), 4u) << what;
  for (const MatchScore& s : scores) {
    EXPECT_DOUBLE_EQ(s.precision, precision) << what << " at " << s.threshold.distance_mm << " mm";
    EXPECT_DOUBLE_EQ(s.recall, recall) << what << " at " << s.threshold.distance_mm << " mm";
  }
}

StrandEvaluation Evaluate(const StrandSet& estimate, const StrandSet& truth,
                          const std::vector<uint8_t>& visible = {},
                          const HeadModel* head = nullptr) {
  auto e = EvaluateStrands(estimate, truth, visible, head, {});
  EXPECT_TRUE(e.ok()) << e.status().ToString();
  return e.ok() ? *e : StrandEvaluation{};
}

TEST(StrandEvaluation, TheProtocolsThresholds) {
  const std::vector<MatchThreshold> t = StrandMatchThresholds();
  ASSERT_EQ(t.size(), 4u);
  const double expected[4][2] = {{2, 20}, {3, 30}, {4, 40}, {4, 90}};
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(t[k].distance_mm, expected[k][0]);
    EXPECT_EQ(t[k].angle_deg, expected[k][1]);
  }
}

TEST(StrandEvaluation, IdenticalStrandsScoreOneDirectedAndUndirected) {
  const StrandSet truth = Comb(6, 20);
  const StrandEvaluation e = Evaluate(truth, truth, std::vector<uint8_t>(120, 1));
  EXPECT_EQ(e.strands, 6);
  EXPECT_EQ(e.samples, 120);  // 19 segments of 1 mm and the tip
  EXPECT_EQ(e.truth_samples, 120);
  ASSERT_TRUE(e.visible_truth_samples.has_value());
  EXPECT_EQ(*e.visible_truth_samples, 120);
  ExpectAll(e.all.undirected, 1, 1, "all, undirected");
  ExpectAll(e.all.directed, 1, 1, "all, directed");
  ExpectAll(e.visible.undirected, 1, 1, "visible, undirected");
  ExpectAll(e.visible.directed, 1, 1, "visible, directed");
  EXPECT_DOUBLE_EQ(e.consistency, 1);
  EXPECT_EQ(e.consistency_strands, 6);
  EXPECT_FALSE(e.rooted_on_scalp_fraction.has_value()) << "no head: not scored";
  EXPECT_EQ(e.lengths.count, 6);
  EXPECT_DOUBLE_EQ(e.lengths.mean_mm, 19);
  EXPECT_DOUBLE_EQ(e.truth_lengths.median_mm, 19);
}

TEST(StrandEvaluation, ReversedStrandsMatchOnlyWhenTheSignDoesNotCount) {
  const StrandSet truth = Comb(6, 20);
  StrandSet reversed;
  for (std::vector<Eigen::Vector3f> s : Strands(truth)) {
    std::reverse(s.begin(), s.end());
    reversed.AddStrand(s);
  }
  const StrandEvaluation e = Evaluate(reversed, truth);
  ExpectAll(e.all.undirected, 1, 1, "undirected");
  // Every reversed sample points exactly against its true one (180 deg), so
  // no threshold matches it, 90 deg included.
  ExpectAll(e.all.directed, 0, 0, "directed");
  EXPECT_DOUBLE_EQ(e.consistency, 1) << "consistency is undirected";
  EXPECT_FALSE(e.visible_truth_samples.has_value());
  EXPECT_TRUE(e.visible.undirected.empty());
}

TEST(StrandEvaluation, StrandsDisplacedBy5mmScoreZeroAt4mm) {
  const StrandSet truth = Comb(6, 20);
  StrandSet displaced = truth;
  for (Eigen::Vector3f& p : displaced.points_mm) p.y() += 5;  // across the strands and the comb
  const StrandEvaluation e = Evaluate(displaced, truth);
  ExpectAll(e.all.undirected, 0, 0, "undirected");
  ExpectAll(e.all.directed, 0, 0, "directed");
  EXPECT_EQ(e.consistency_strands, 0);
  EXPECT_DOUBLE_EQ(e.consistency, 0);
}

TEST(StrandEvaluation, AStrandCutInTwoHalvesIsHalfConsistent) {
  const StrandSet truth = Comb(6, 20);
  StrandSet halves;
  for (const std::vector<Eigen::Vector3f>& s : Strands(truth)) {
    halves.AddStrand(
        std::vector<Eigen::Vector3f>(s.begin(), s.begin() + 10));  // z = 0..9: 10 samples
    halves.AddStrand(
        std::vector<Eigen::Vector3f>(s.begin() + 10, s.end()));  // z = 10..19: 10 samples
  }
  const StrandEvaluation e = Evaluate(halves, truth);
  // Every true sample has an estimate sample at distance 0 (the nearest),
  // from the half it lies in: 10 of 20 from each.
  ExpectAll(e.all.undirected, 1, 1, "undirected");
  ExpectAll(e.all.directed, 1, 1, "directed");
  EXPECT_EQ(e.consistency_strands, 6);
  EXPECT_DOUBLE_EQ(e.consistency, 0.5);
  EXPECT_EQ(e.strands, 12);
  EXPECT_DOUBLE_EQ(e.lengths.mean_mm, 9);
}

// `count` strands up +z, 60 points 1 mm apart, 1 mm apart along x (every
// odd one shifted 0.3 mm towards the next, so no sample is equally near two
// even ones), each swaying along x by `sway_mm` with its own phase.
StrandSet SwayingStrands(int count, double sway_mm) {
  StrandSet set;
  for (int i = 0; i < count; ++i) {
    std::vector<Eigen::Vector3f> strand;
    const double x0 = i + (i % 2 == 1 ? 0.3 : 0.0), phase = 2.4 * i;
    for (int k = 0; k < 60; ++k) {
      strand.emplace_back(static_cast<float>(x0 + sway_mm * std::sin(0.3 * k + phase)), 0.f,
                          static_cast<float>(k));
    }
    set.AddStrand(strand);
  }
  return set;
}

TEST(StrandEvaluation, TheTruthsOwnConsistencyFallsWhenItsStrandsWeave) {
  const StrandEvalOptions options;
  const auto straight = ConsistencyOfTruthSubset(SwayingStrands(20, 0), 10, options);
  ASSERT_TRUE(straight.ok()) << straight.status().ToString();
  EXPECT_DOUBLE_EQ(straight->consistency, 1.0);  // each odd strand keeps its nearest even one
  EXPECT_EQ(straight->kept_strands, 10);
  EXPECT_EQ(straight->scored_strands, 10);
  const auto half = ConsistencyOfTruthSubset(SwayingStrands(20, 1.5), 10, options);
  const auto quarter = ConsistencyOfTruthSubset(SwayingStrands(20, 1.5), 5, options);
  ASSERT_TRUE(half.ok() && quarter.ok());
  std::printf("consistency of the truth's own weaving strands: half kept %.3f, a quarter %.3f\n",
              half->consistency, quarter->consistency);
  EXPECT_NEAR(half->consistency, 0.46, 0.05);
  EXPECT_EQ(quarter->kept_strands, 5);
  EXPECT_GT(quarter->consistency, half->consistency + 0.05);  // fewer kept: fewer to change hands
  EXPECT_EQ(ConsistencyOfTruthSubset(SwayingStrands(4, 0), 0, options).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(StrandEvaluation, VisibleSurfaceRecallCountsTheMaskedTruthAndKeepsThePrecision) {
  const StrandSet truth = Comb(6, 20);
  StrandSet first_three;
  const auto strands = Strands(truth);
  for (size_t s = 0; s < 3; ++s) first_three.AddStrand(strands[s]);
  std::vector<uint32_t> strand_of;
  SampleStrands(truth, 1.0, &strand_of);
  std::vector<uint8_t> visible;
  for (uint32_t s : strand_of) visible.push_back(static_cast<uint8_t>(s < 3));
  const StrandEvaluation e = Evaluate(first_three, truth, visible);
  ASSERT_TRUE(e.visible_truth_samples.has_value());
  EXPECT_EQ(*e.visible_truth_samples, 60);
  ExpectAll(e.all.undirected, 1, 0.5, "all");
  ExpectAll(e.visible.undirected, 1, 1, "visible");
  ExpectAll(e.visible.directed, 1, 1, "visible, directed");
  EXPECT_EQ(e.consistency_strands, 3);

  // The other half seen: nothing of it reconstructed, the precision unchanged.
  for (uint8_t& v : visible) v = static_cast<uint8_t>(v == 0);
  const StrandEvaluation other = Evaluate(first_three, truth, visible);
  ExpectAll(other.visible.undirected, 1, 0, "the other half visible");
}

TEST(StrandEvaluation, TheShareOfRootsOnTheScalpOfAnEllipsoidHead) {
  HeadSpec spec;  // no mesh: the ellipsoid centred at (0, 0, 250), radii (78, 95, 115)
  spec.scalp.defined = true;
  spec.scalp.center_turntable_mm = spec.center_turntable_mm;
  spec.scalp.face_dir = Eigen::Vector3d(0, -1, 0);
  spec.scalp.parting = false;
  auto head = HeadModel::Build(spec);
  ASSERT_TRUE(head.ok()) << head.status().ToString();
  const auto strand = [](const Eigen::Vector3f& root, const Eigen::Vector3f& outward) {
    return std::vector<Eigen::Vector3f>{root, root + 20.f * outward};
  };
  const Eigen::Vector3f up = Eigen::Vector3f::UnitZ(), forward(0, -1, 0);
  StrandSet estimate;
  estimate.AddStrand(strand({0, 0, 365}, up));  // the crown: on the scalp
  estimate.AddStrand(strand({0, 0, 367}, up));  // 2 mm above it: within 3 mm
  estimate.AddStrand(
      strand({0, -95, 250}, forward));  // the face: on the head, below the hairline (38 deg)
  estimate.AddStrand(strand({0, 0, 375}, up));  // 10 mm above the crown: off the head
  const StrandEvaluation e = Evaluate(estimate, Comb(2, 5), {}, head->get());
  ASSERT_TRUE(e.rooted_on_scalp_fraction.has_value());
  EXPECT_DOUBLE_EQ(*e.rooted_on_scalp_fraction, 0.5);
  EXPECT_EQ(e.rooted_on_scalp, 2);
  EXPECT_DOUBLE_EQ(e.root_tolerance_mm, 3);
  EXPECT_FALSE(e.ToJson()["rooted_on_scalp"].is_null());
  EXPECT_TRUE(Evaluate(estimate, Comb(2, 5)).ToJson()["rooted_on_scalp"].is_null());
}

TEST(StrandEvaluation, LengthQuantilesAndAnEmptyReconstruction) {
  StrandSet truth;
  for (int i = 1; i <= 10; ++i) {
    const auto x = static_cast<float>(10 * i);
    truth.AddStrand({{x, 0, 0}, {x, 0, static_cast<float>(10 * i)}});  // 10, 20, ..., 100 mm
  }
  const StrandEvaluation e = Evaluate(StrandSet{}, truth);
  EXPECT_EQ(e.truth_lengths.count, 10);
  EXPECT_DOUBLE_EQ(e.truth_lengths.mean_mm, 55);
  EXPECT_DOUBLE_EQ(e.truth_lengths.p10_mm, 20);  // the element at floor(0.1 * 10) once sorted
  EXPECT_DOUBLE_EQ(e.truth_lengths.median_mm, 60);
  EXPECT_DOUBLE_EQ(e.truth_lengths.p90_mm, 100);
  EXPECT_EQ(e.lengths.count, 0);
  EXPECT_DOUBLE_EQ(e.lengths.mean_mm, 0);
  ExpectAll(e.all.undirected, 0, 0, "nothing reconstructed");
  EXPECT_EQ(e.consistency_strands, 0);
}

TEST(StrandEvaluation, BadOptionsMasksAndStrandSetsAreRefused) {
  const StrandSet truth = Comb(2, 5);
  StrandEvalOptions options;
  options.sample_step_mm = 0;
  auto e = EvaluateStrands(truth, truth, {}, nullptr, options);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(e.status().message().find("sample_step_mm"), std::string::npos) << e.status().message();

  e = EvaluateStrands(truth, truth, std::vector<uint8_t>(3, 1), nullptr, {});  // 10 true samples
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.status().message().find("mask"), std::string::npos) << e.status().message();

  StrandSet broken = truth;
  broken.point_counts.push_back(4);  // points that are not there
  e = EvaluateStrands(broken, truth, {}, nullptr, {});
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.status().message().find("reconstructed strands"), std::string::npos)
      << e.status().message();

  std::vector<uint32_t> strand_of;
  const std::vector<OrientedSample> samples = SampleStrands(truth, 1.0, &strand_of);
  strand_of.back() = 2;  // there are two true strands
  e = EvaluateStrands(truth, truth, samples, strand_of, {}, nullptr, {});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kInvalidArgument);
}

TEST(StrandEvaluation, TheReportAndTheJsonCarryEveryScore) {
  const StrandSet truth = Comb(3, 10);
  const StrandEvaluation e = Evaluate(truth, truth, std::vector<uint8_t>(30, 1));
  const nlohmann::json j = e.ToJson();
  EXPECT_EQ(j["all_strands"]["undirected"].size(), 4u);
  EXPECT_EQ(j["all_strands"]["directed"].size(), 4u);
  EXPECT_EQ(j["visible_surface"]["directed"].size(), 4u);
  EXPECT_DOUBLE_EQ(j["all_strands"]["directed"][0]["precision"].get<double>(), 1);
  EXPECT_DOUBLE_EQ(j["consistency"]["mean"].get<double>(), 1);
  EXPECT_EQ(j["lengths_mm"]["truth"]["count"].get<int>(), 3);
  EXPECT_TRUE(j["rooted_on_scalp"].is_null());
  EXPECT_TRUE(Evaluate(truth, truth).ToJson()["visible_surface"].is_null());
  const std::string report = e.BriefReport();
  for (const char* part : {"(2 mm, 20 deg)", "(4 mm, 90 deg)", "visible-surface recall",
                           "consistency", "not scored", "lengths"})
    EXPECT_NE(report.find(part), std::string::npos) << part << " in\n" << report;
}

}  // namespace
}  // namespace hairrig
