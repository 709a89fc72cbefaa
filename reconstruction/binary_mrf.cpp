#include "reconstruction/binary_mrf.h"

#include <maxflow.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace hairrig {

namespace {

// What a pair prefers: + equal labels, - different ones.
double Preference(const BinaryMrfPair& pair) { return pair.cost_differ - pair.cost_equal; }

// Relabelling flips (+1 keep, -1 swap the labels) that make every edge of a
// maximum spanning tree of |preference| submodular.
std::vector<int> SpanningTreeFlips(size_t n, const std::vector<BinaryMrfPair>& pairs) {
  std::vector<size_t> order(pairs.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return std::abs(Preference(pairs[x])) > std::abs(Preference(pairs[y]));
  });
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<std::vector<std::pair<uint32_t, int>>> tree(n);
  for (size_t k : order) {
    const BinaryMrfPair& pair = pairs[k];
    const uint32_t a = find(pair.a), b = find(pair.b);
    if (a == b) continue;
    parent[a] = b;
    const int sign = Preference(pair) >= 0 ? 1 : -1;
    tree[pair.a].emplace_back(pair.b, sign);
    tree[pair.b].emplace_back(pair.a, sign);
  }
  std::vector<int> flip(n, 0);
  std::vector<uint32_t> stack;
  for (uint32_t root = 0; root < n; ++root) {
    if (flip[root] != 0) continue;
    flip[root] = 1;
    stack.push_back(root);
    while (!stack.empty()) {
      const uint32_t u = stack.back();
      stack.pop_back();
      for (const auto& [v, sign] : tree[u]) {
        if (flip[v] != 0) continue;
        flip[v] = flip[u] * sign;
        stack.push_back(v);
      }
    }
  }
  return flip;
}

double Energy(const BinaryMrf& mrf, const std::vector<uint8_t>& labels) {
  double energy = 0;
  for (size_t i = 0; i < mrf.unary.size(); ++i) energy += mrf.unary[i][labels[i]];
  for (const BinaryMrfPair& pair : mrf.pairs) {
    energy += labels[pair.a] == labels[pair.b] ? pair.cost_equal : pair.cost_differ;
  }
  return energy;
}

}  // namespace

BinaryMrfSolution SolveBinaryMrf(const BinaryMrf& mrf) {
  BinaryMrfSolution solution;
  const size_t n = mrf.unary.size();
  if (n == 0) return solution;
  const std::vector<int> flip = SpanningTreeFlips(n, mrf.pairs);

  // In the relabelled problem label 0 (source side) keeps a node's tree
  // orientation, label 1 (sink side) swaps it.
  maxflow::Graph_DDD graph(static_cast<int>(n), static_cast<int>(mrf.pairs.size()));
  graph.add_node(static_cast<int>(n));
  for (size_t i = 0; i < n; ++i) {
    const bool swapped = flip[i] < 0;
    const double cost0 = mrf.unary[i][swapped ? 1 : 0], cost1 = mrf.unary[i][swapped ? 0 : 1];
    const double floor = std::min(cost0, cost1);
    // Being on the sink side (label 1) cuts the source edge: its capacity is label 1's cost.
    graph.add_tweights(static_cast<int>(i), cost1 - floor, cost0 - floor);
  }
  for (const BinaryMrfPair& pair : mrf.pairs) {
    const bool swapped = flip[pair.a] != flip[pair.b];
    const double preference = swapped ? -Preference(pair) : Preference(pair);
    if (preference <= 0) {
      if (preference < 0) ++solution.truncated_pairs;
      continue;
    }
    graph.add_edge(static_cast<int>(pair.a), static_cast<int>(pair.b), preference, preference);
  }
  solution.cut = graph.maxflow();
  solution.labels.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const bool sink = graph.what_segment(static_cast<int>(i)) == maxflow::Graph_DDD::SINK;
    solution.labels[i] = static_cast<uint8_t>(sink != (flip[i] < 0));
  }
  solution.energy = Energy(mrf, solution.labels);
  return solution;
}

}  // namespace hairrig
