#include "reconstruction/strand_direction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <utility>

#include <maxflow.h>

#include "core/parallel.h"
#include "reconstruction/point_grid.h"

namespace hairrig {

namespace {

using PairKey = std::pair<uint32_t, uint32_t>;
// The signed weight of one relation between two segments (lower index
// first): + where their vertex orders agree (the same label is compatible),
// - where they oppose. MergePairs sums the relations of each pair.
using PairWeights = std::vector<std::pair<PairKey, double>>;

void MergePairs(PairWeights* pairs) {
  std::sort(pairs->begin(), pairs->end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  size_t out = 0;
  for (size_t i = 0; i < pairs->size(); ++i) {
    if (out > 0 && (*pairs)[out - 1].first == (*pairs)[i].first) {
      (*pairs)[out - 1].second += (*pairs)[i].second;
    } else {
      (*pairs)[out++] = (*pairs)[i];
    }
  }
  pairs->resize(out);
}

// Distance to the scalp (zeta of Eq. 5): to the nearest of a dense sample of it.
class ScalpDistance {
 public:
  explicit ScalpDistance(const HeadModel* head) {
    if (head == nullptr) return;
    std::mt19937_64 rng(17);
    samples_.resize(4000);
    for (Eigen::Vector3f& s : samples_) {
      Eigen::Vector3d normal;
      s = head->SampleScalp(rng, &normal).cast<float>();
    }
  }
  bool available() const { return !samples_.empty(); }
  double operator()(const Eigen::Vector3f& p) const {
    float best = std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& s : samples_) best = std::min(best, (s - p).squaredNorm());
    return samples_.empty() ? 0.0 : std::sqrt(best);
  }

 private:
  std::vector<Eigen::Vector3f> samples_;
};

// E_ribb (Eq. 5) of keeping each segment's vertex order.
std::vector<double> KeepEnergies(const std::vector<StrandSegment>& segments, const HeadModel* head,
                                 const DirectionOptions& o) {
  const ScalpDistance zeta(head);
  std::vector<double> keep(segments.size());
  ParallelFor(segments.size(), o.threads, [&] {
    return [&](size_t i) {
      const Eigen::Vector3f& first = segments[i].points_mm.front();
      const Eigen::Vector3f& last = segments[i].points_mm.back();
      double e = first.dot(o.down) - last.dot(o.down);
      if (zeta.available()) e += zeta(first) - zeta(last);
      keep[i] = e / (2 * o.height_scale_mm);
    };
  });
  return keep;
}

Eigen::Vector3f Tangent(const std::vector<Eigen::Vector3f>& p, size_t i) {
  const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, p.size() - 1);
  const Eigen::Vector3f d = p[b] - p[a];
  return d.norm() > 0 ? Eigen::Vector3f(d.normalized()) : Eigen::Vector3f::Zero();
}

// Every segment's vertices in one table, with their tangents and owners.
struct VertexTable {
  std::vector<Eigen::Vector3f> positions, tangents;
  std::vector<uint32_t> owner;
  std::vector<uint32_t> first;  // per segment, its first row; one past the end last
};

VertexTable TabulateVertices(const std::vector<StrandSegment>& segments) {
  VertexTable t;
  for (uint32_t s = 0; s < segments.size(); ++s) {
    t.first.push_back(static_cast<uint32_t>(t.positions.size()));
    const auto& points = segments[s].points_mm;
    for (size_t k = 0; k < points.size(); ++k) {
      t.positions.push_back(points[k]);
      t.tangents.push_back(Tangent(points, k));
      t.owner.push_back(s);
    }
  }
  t.first.push_back(static_cast<uint32_t>(t.positions.size()));
  return t;
}

// Per other segment that a segment overlaps: how many of its queried vertices
// have that segment within reach, and the vote of their tangents (+1 agree, -1 oppose).
struct OverlapTally {
  uint32_t other = 0;
  int overlapped = 0, votes = 0;
};

// Tallies one segment's overlaps at a time. Per-segment marks (which query,
// which tally last saw that segment) make every lookup O(1); one per thread.
class OverlapTallier {
 public:
  OverlapTallier(const VertexTable& table, const PointGrid& grid, const DirectionOptions& o)
      : table_(table), grid_(grid), o_(o) {
    const size_t n = table.first.size() - 1;
    query_mark_.assign(n, kNone);
    query_slot_.assign(n, 0);
    tally_mark_.assign(n, kNone);
    tally_slot_.assign(n, 0);
  }

  std::vector<OverlapTally> Tally(uint32_t s) {
    std::vector<OverlapTally> tallies;
    const uint32_t stride = static_cast<uint32_t>(o_.overlap_stride);
    for (uint32_t v = table_.first[s]; v < table_.first[s + 1]; v += stride) {
      NearestOthers(s, v);
      for (const Near& n : nearest_) {
        if (tally_mark_[n.segment] != s) {
          tally_mark_[n.segment] = s;
          tally_slot_[n.segment] = static_cast<uint32_t>(tallies.size());
          tallies.push_back({n.segment, 0, 0});
        }
        OverlapTally& t = tallies[tally_slot_[n.segment]];
        ++t.overlapped;
        t.votes += table_.tangents[v].dot(table_.tangents[n.vertex]) >= 0 ? 1 : -1;
      }
    }
    std::sort(tallies.begin(), tallies.end(), [](const OverlapTally& a, const OverlapTally& b) { return a.other < b.other; });
    return tallies;
  }

 private:
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  struct Near {
    uint32_t segment, vertex;
    double d2;
  };

  // nearest_: per other segment within reach of vertex v, its nearest vertex.
  void NearestOthers(uint32_t s, uint32_t v) {
    nearest_.clear();
    ++query_id_;
    grid_.ForEachWithin(table_.positions[v], o_.overlap_mm, [&](uint32_t u, double d2) {
      const uint32_t other = table_.owner[u];
      if (other == s) return;
      if (query_mark_[other] != query_id_) {
        query_mark_[other] = query_id_;
        query_slot_[other] = static_cast<uint32_t>(nearest_.size());
        nearest_.push_back({other, u, d2});
      } else if (d2 < nearest_[query_slot_[other]].d2) {
        nearest_[query_slot_[other]].vertex = u;
        nearest_[query_slot_[other]].d2 = d2;
      }
    });
  }

  const VertexTable& table_;
  const PointGrid& grid_;
  const DirectionOptions& o_;
  std::vector<uint32_t> query_mark_, query_slot_, tally_mark_, tally_slot_;
  std::vector<Near> nearest_;
  uint32_t query_id_ = 0;
};

// E_close (Eq. 7): side-by-side segments, weighted by their overlap share
// (of the vertices queried: every overlap_stride-th).
void AddOverlaps(const std::vector<StrandSegment>& segments, const DirectionOptions& o,
                 PairWeights* pairs, int64_t* count) {
  const VertexTable table = TabulateVertices(segments);
  const PointGrid grid(table.positions, o.overlap_mm);
  std::vector<std::vector<OverlapTally>> seen(segments.size());
  ParallelFor(segments.size(), o.threads, [&] {
    auto tallier = std::make_shared<OverlapTallier>(table, grid, o);
    return [&seen, tallier](size_t s) { seen[s] = tallier->Tally(static_cast<uint32_t>(s)); };
  });
  const auto queried = [&](uint32_t s) {
    const uint32_t n = table.first[s + 1] - table.first[s];
    return (n + static_cast<uint32_t>(o.overlap_stride) - 1) / static_cast<uint32_t>(o.overlap_stride);
  };
  const auto by_other = [](const OverlapTally& t, uint32_t other) { return t.other < other; };
  for (uint32_t s = 0; s < segments.size(); ++s) {
    for (const OverlapTally& tally : seen[s]) {
      if (tally.other < s) continue;  // each pair once, from its lower index; the other side's count joins it
      int overlapped = tally.overlapped, votes = tally.votes;
      const auto& back_list = seen[tally.other];
      const auto back = std::lower_bound(back_list.begin(), back_list.end(), s, by_other);
      if (back != back_list.end() && back->other == s) overlapped += back->overlapped, votes += back->votes;
      if (votes == 0) continue;
      const double eta = static_cast<double>(overlapped) / static_cast<double>(queried(s) + queried(tally.other));
      pairs->push_back({{s, tally.other}, (votes > 0 ? 1 : -1) * o.alpha_close * eta});
      ++*count;
    }
  }
}

// E_link (Eq. 6): a segment's end continues into another's end across a small gap.
void AddLinks(const std::vector<StrandSegment>& segments, const DirectionOptions& o,
              PairWeights* pairs, int64_t* count) {
  std::vector<Eigen::Vector3f> ends;
  std::vector<Eigen::Vector3f> outward;  // the tangent leaving the segment at that end
  for (const StrandSegment& s : segments) {
    const auto& p = s.points_mm;
    ends.push_back(p.front());
    outward.push_back(-Tangent(p, 0));
    ends.push_back(p.back());
    outward.push_back(Tangent(p, p.size() - 1));
  }
  const PointGrid grid(ends, o.link_gap_mm);
  for (uint32_t e = 0; e < ends.size(); ++e) {
    grid.ForEachWithin(ends[e], o.link_gap_mm, [&](uint32_t f, double d2) {
      if (f <= e || f / 2 == e / 2) return;
      if (outward[e].dot(-outward[f]) < o.link_cos) return;
      if (d2 > 0.25) {
        const Eigen::Vector3f gap = (ends[f] - ends[e]).normalized();
        if (outward[e].dot(gap) < o.link_cos || outward[f].dot(-gap) < o.link_cos) return;
      }
      // A last end meeting a first end keeps both orders; two firsts or two lasts oppose them.
      const bool aligned = (e % 2) != (f % 2);
      pairs->push_back({{e / 2, f / 2}, (aligned ? 1 : -1) * o.alpha_link});
      ++*count;
    });
  }
}

// Orientation flips (+1 keep, -1 reverse) that make every edge of a maximum
// spanning tree of |weight| aligned.
std::vector<int> SpanningTreeOrientation(size_t n, PairWeights pairs) {
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const auto& a, const auto& b) { return std::abs(a.second) > std::abs(b.second); });
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<std::vector<std::pair<uint32_t, int>>> tree(n);
  for (const auto& [key, weight] : pairs) {
    const uint32_t a = find(key.first), b = find(key.second);
    if (a == b) continue;
    parent[a] = b;
    const int sign = weight >= 0 ? 1 : -1;
    tree[key.first].emplace_back(key.second, sign);
    tree[key.second].emplace_back(key.first, sign);
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

}  // namespace

Status DirectionOptions::Check() const {
  if (!(height_scale_mm > 0)) return InvalidArgument("direction height_scale_mm must be positive");
  if (!(alpha_link >= 0) || !(alpha_close >= 0)) return InvalidArgument("direction weights must be non-negative");
  if (overlap_stride < 1) return InvalidArgument("direction overlap_stride must be at least 1");
  if (!(link_gap_mm > 0) || !(overlap_mm > 0)) return InvalidArgument("direction link_gap_mm and overlap_mm must be positive");
  if (!(link_cos >= 0 && link_cos <= 1)) return InvalidArgument("direction link_cos must lie in 0..1");
  if (!(std::abs(down.norm() - 1) < 1e-3)) return InvalidArgument("direction down must be a unit vector");
  return Status::Ok();
}

DirectionSummary DirectSegments(std::vector<StrandSegment>* segments, const HeadModel* head,
                                const DirectionOptions& o) {
  DirectionSummary summary;
  const size_t n = segments->size();
  summary.segments = static_cast<int64_t>(n);
  if (n == 0) return summary;
  const std::vector<double> keep = KeepEnergies(*segments, head, o);
  PairWeights pairs;
  AddOverlaps(*segments, o, &pairs, &summary.overlaps);
  AddLinks(*segments, o, &pairs, &summary.links);
  MergePairs(&pairs);
  const std::vector<int> orient = SpanningTreeOrientation(n, pairs);

  // Labels relative to the tree's orientation: 0 (source side) keeps it, 1 reverses it.
  maxflow::Graph_DDD graph(static_cast<int>(n), static_cast<int>(pairs.size()));
  graph.add_node(static_cast<int>(n));
  for (size_t i = 0; i < n; ++i) {
    const double cost_keep = keep[i] * orient[i], cost_reverse = -cost_keep;
    const double floor = std::min(cost_keep, cost_reverse);
    // Being on the sink side (label 1) cuts the source edge: its capacity is label 1's cost.
    graph.add_tweights(static_cast<int>(i), cost_reverse - floor, cost_keep - floor);
  }
  for (const auto& [key, weight] : pairs) {
    const double aligned = weight * orient[key.first] * orient[key.second];
    if (aligned <= 0) {
      if (aligned < 0) ++summary.truncated_pairs;
      continue;
    }
    graph.add_edge(static_cast<int>(key.first), static_cast<int>(key.second), aligned, aligned);
  }
  summary.energy = graph.maxflow();
  for (size_t i = 0; i < n; ++i) {
    const bool reverse_tree = graph.what_segment(static_cast<int>(i)) == maxflow::Graph_DDD::SINK;
    const int final_orientation = orient[i] * (reverse_tree ? -1 : 1);
    if (final_orientation < 0) {
      std::reverse((*segments)[i].points_mm.begin(), (*segments)[i].points_mm.end());
      ++summary.reversed;
    }
    if (keep[i] * final_orientation > 0) ++summary.unary_disagreements;
  }
  return summary;
}

}  // namespace hairrig
