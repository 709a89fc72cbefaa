#include "reconstruction/binary_mrf.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace hairrig {
namespace {

double EnergyOf(const BinaryMrf& mrf, uint32_t labels_bits) {
  const auto label = [&](uint32_t i) { return (labels_bits >> i) & 1u; };
  double e = 0;
  for (uint32_t i = 0; i < mrf.unary.size(); ++i) e += mrf.unary[i][label(i)];
  for (const BinaryMrfPair& p : mrf.pairs)
    e += label(p.a) == label(p.b) ? p.cost_equal : p.cost_differ;
  return e;
}

double BruteForceMinimum(const BinaryMrf& mrf) {
  double best = std::numeric_limits<double>::max();
  for (uint32_t bits = 0; bits < (1u << mrf.unary.size()); ++bits)
    best = std::min(best, EnergyOf(mrf, bits));
  return best;
}

TEST(BinaryMrf, ExactOnTreesWhatEverThePairsPrefer) {
  // Random trees: relabelling along the spanning tree makes every pair
  // submodular, so the cut is a global minimum even where pairs prefer
  // different labels.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> cost(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    BinaryMrf mrf;
    const uint32_t n = 9;
    for (uint32_t i = 0; i < n; ++i) mrf.unary.push_back({cost(rng), cost(rng)});
    for (uint32_t i = 1; i < n; ++i) {
      mrf.pairs.push_back(
          {static_cast<uint32_t>(rng() % i), i, std::abs(cost(rng)), std::abs(cost(rng))});
    }
    const BinaryMrfSolution solution = SolveBinaryMrf(mrf);
    ASSERT_EQ(solution.labels.size(), n);
    EXPECT_EQ(solution.truncated_pairs, 0);
    uint32_t bits = 0;
    for (uint32_t i = 0; i < n; ++i) bits |= static_cast<uint32_t>(solution.labels[i]) << i;
    EXPECT_NEAR(solution.energy, EnergyOf(mrf, bits), 1e-12);
    EXPECT_NEAR(solution.energy, BruteForceMinimum(mrf), 1e-9) << "trial " << trial;
  }
}

TEST(BinaryMrf, AFrustratedCycleIsTruncatedNotIgnored) {
  // Three nodes that all want to differ from each other: no labelling
  // satisfies all three; one pair is truncated, and the strong unary on
  // node 0 still decides it.
  BinaryMrf mrf;
  mrf.unary = {{0.0, 5.0}, {0.0, 0.0}, {0.0, 0.0}};
  mrf.pairs = {{0, 1, 1.0, 0.0}, {1, 2, 1.0, 0.0}, {0, 2, 1.0, 0.0}};
  const BinaryMrfSolution solution = SolveBinaryMrf(mrf);
  EXPECT_EQ(solution.truncated_pairs, 1);
  EXPECT_EQ(solution.labels[0], 0);
  EXPECT_NEAR(solution.energy, BruteForceMinimum(mrf), 1e-12);  // 1: one pair must stay equal
}

}  // namespace
}  // namespace hairrig
