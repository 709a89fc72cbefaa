// A two-label Markov random field solved by one graph cut (Boykov-Kolmogorov
// max-flow, Debian's libmaxflow): the solver behind Luo et al. 2013 Sec. 6.2's
// direction analysis, for strand segments (strand_direction.h) and for
// ribbons (ribbons.h).
//
// Energy: sum_i unary_i(x_i) + sum_pairs (x_a == x_b ? cost_equal : cost_differ),
// x_i in {0, 1}. A pair is submodular when cost_equal <= cost_differ.
// Relabelling a node (0 <-> 1) swaps the equal and differ costs of its pairs,
// so the nodes are first relabelled along a maximum spanning tree of
// |cost_differ - cost_equal| to make the strongest pairs submodular; the pairs
// that stay non-submodular are truncated (Rother et al. 2005: their excess
// cost_equal - cost_differ is dropped), and the cut is exact for the
// truncated energy. Without non-submodular cycles nothing is truncated and
// the labels are a global minimum.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace hairrig {

struct BinaryMrfPair {
  uint32_t a = 0, b = 0;  // node indices, a != b
  double cost_equal = 0, cost_differ = 0;
};

struct BinaryMrf {
  std::vector<std::array<double, 2>> unary;  // per node: the cost of label 0 and of label 1
  // Any order; a pair of nodes may repeat (the terms add). The spanning tree
  // takes the strongest pairs first, ties in this order.
  std::vector<BinaryMrfPair> pairs;
};

struct BinaryMrfSolution {
  std::vector<uint8_t> labels;  // per node, 0 or 1
  double energy = 0;            // the full energy at `labels` (truncated terms included)
  // The minimum cut: the truncated energy at `labels` less its floor (every
  // unary's and every pair's smaller cost).
  double cut = 0;
  int64_t truncated_pairs = 0;  // pairs left non-submodular by the relabelling
};

// Finite costs are the caller's to ensure. Deterministic.
BinaryMrfSolution SolveBinaryMrf(const BinaryMrf& mrf);

}  // namespace hairrig
