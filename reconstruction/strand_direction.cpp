#include "reconstruction/strand_direction.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/parallel.h"
#include "reconstruction/binary_mrf.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/polyline_overlap.h"
#include "reconstruction/scalp_distance.h"

namespace hairrig {

namespace {

using PairKey = std::pair<uint32_t, uint32_t>;
// The signed weight of one relation between two segments (lower index
// first): + where their vertex orders agree (the same label is compatible),
// - where they oppose. MergePairs sums the relations of each pair.
using PairWeights = std::vector<std::pair<PairKey, double>>;

void MergePairs(PairWeights* pairs) {
  std::sort(pairs->begin(), pairs->end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
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

// E_close (Eq. 7): side-by-side segments, weighted by their overlap share
// (of the vertices queried: every overlap_stride-th), each segment's
// max_overlaps strongest kept. With share_overlaps, each kept overlap is
// divided by the larger of its two segments' summed kept shares (when over 1).
void AddOverlaps(const std::vector<StrandSegment>& segments, const DirectionOptions& o,
                 PairWeights* pairs, int64_t* found, int64_t* count) {
  std::vector<const std::vector<Eigen::Vector3f>*> polylines;
  for (const StrandSegment& s : segments) polylines.push_back(&s.points_mm);
  const PolylineVertexTable table = TabulatePolylines(polylines);
  std::vector<OwnerOverlap> overlaps =
      FindOwnerOverlaps(table, o.overlap_mm, o.overlap_stride, o.threads);
  overlaps.erase(std::remove_if(overlaps.begin(), overlaps.end(),
                                [](const OwnerOverlap& v) { return v.votes == 0; }),
                 overlaps.end());
  *found += static_cast<int64_t>(overlaps.size());
  if (o.max_overlaps > 0) KeepStrongestOverlaps(segments.size(), o.max_overlaps, &overlaps);
  std::vector<double> total(segments.size(), 0.0);
  for (const OwnerOverlap& overlap : overlaps) {
    total[overlap.a] += overlap.share;
    total[overlap.b] += overlap.share;
  }
  for (const OwnerOverlap& overlap : overlaps) {
    const double norm =
        o.share_overlaps ? 1.0 / std::max({1.0, total[overlap.a], total[overlap.b]}) : 1.0;
    pairs->push_back({{overlap.a, overlap.b},
                      (overlap.votes > 0 ? 1 : -1) * o.alpha_close * overlap.share * norm});
  }
  *count += static_cast<int64_t>(overlaps.size());
}

// E_link (Eq. 6): a segment's end continues into another's end across a small gap.
// With share_link_ends, an end's links share alpha_link: each weighs
// alpha_link / (the larger number of links at either of its two ends).
void AddLinks(const std::vector<StrandSegment>& segments, const DirectionOptions& o,
              PairWeights* pairs, int64_t* count) {
  std::vector<Eigen::Vector3f> ends;
  std::vector<Eigen::Vector3f> outward;  // the tangent leaving the segment at that end
  for (const StrandSegment& s : segments) {
    const auto& p = s.points_mm;
    ends.push_back(p.front());
    outward.push_back(-PolylineTangent(p, 0));
    ends.push_back(p.back());
    outward.push_back(PolylineTangent(p, p.size() - 1));
  }
  struct Link {
    uint32_t e, f;
    bool aligned;
  };
  std::vector<Link> links;
  std::vector<int> degree(ends.size(), 0);
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
      links.push_back({e, f, (e % 2) != (f % 2)});
      ++degree[e], ++degree[f];
    });
  }
  for (const Link& link : links) {
    const double share = o.share_link_ends ? 1.0 / std::max(degree[link.e], degree[link.f]) : 1.0;
    pairs->push_back({{link.e / 2, link.f / 2}, (link.aligned ? 1 : -1) * o.alpha_link * share});
  }
  *count += static_cast<int64_t>(links.size());
}

}  // namespace

Status DirectionOptions::Check() const {
  if (!(height_scale_mm > 0)) return InvalidArgument("direction height_scale_mm must be positive");
  if (!(alpha_link >= 0) || !(alpha_close >= 0))
    return InvalidArgument("direction weights must be non-negative");
  if (overlap_stride < 1) return InvalidArgument("direction overlap_stride must be at least 1");
  if (max_overlaps < 0) return InvalidArgument("direction max_overlaps must be 0 (all) or more");
  if (!(link_gap_mm > 0) || !(overlap_mm > 0))
    return InvalidArgument("direction link_gap_mm and overlap_mm must be positive");
  if (!(link_cos >= 0 && link_cos <= 1))
    return InvalidArgument("direction link_cos must lie in 0..1");
  if (!(std::abs(down.norm() - 1) < 1e-3))
    return InvalidArgument("direction down must be a unit vector");
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
  AddOverlaps(*segments, o, &pairs, &summary.overlaps_found, &summary.overlaps);
  AddLinks(*segments, o, &pairs, &summary.links);
  MergePairs(&pairs);

  // Label 0 keeps a segment's vertex order, label 1 reverses it.
  BinaryMrf mrf;
  mrf.unary.resize(n);
  for (size_t i = 0; i < n; ++i) mrf.unary[i] = {keep[i], -keep[i]};
  for (const auto& [key, weight] : pairs) {
    // + weight: the same label is compatible (differing costs it), - weight: the opposite.
    mrf.pairs.push_back(
        {key.first, key.second, weight >= 0 ? 0.0 : -weight, weight >= 0 ? weight : 0.0});
  }
  const BinaryMrfSolution solution = SolveBinaryMrf(mrf);
  summary.truncated_pairs = solution.truncated_pairs;
  summary.energy = solution.cut;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t label = solution.labels[i];
    if (label == 1) {
      std::reverse((*segments)[i].points_mm.begin(), (*segments)[i].points_mm.end());
      ++summary.reversed;
    }
    if (mrf.unary[i][label] > mrf.unary[i][1 - label]) ++summary.unary_disagreements;
  }
  return summary;
}

}  // namespace hairrig
