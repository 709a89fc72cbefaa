// Direction analysis (Sec. 6.2): the ribbons' root-to-tip directions from
// the connection graph's MRF, RibbonOverlap and DirectRibbons of
// reconstruction/ribbons.h.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "core/head_model.h"
#include "reconstruction/binary_mrf.h"
#include "reconstruction/polyline_overlap.h"
#include "reconstruction/ribbons.h"
#include "reconstruction/ribbons_internal.h"
#include "reconstruction/scalp_distance.h"

namespace hairrig {

using detail::Curve;

namespace {

// Whether the link's piece on side k (from the fitted end inwards) runs
// towards increasing l.
bool PieceRunsWithL(const RibbonLink& link, int k) {
  return link.at_first_vertex[k] == link.segment_along_ribbon[k];
}

// A link is compatible with equal directions (both kept or both reversed)
// when exactly one piece runs with its ribbon's l; otherwise with different ones.
bool NeedsEqualDirections(const RibbonLink& link) {
  return PieceRunsWithL(link, 0) != PieceRunsWithL(link, 1);
}

// Eq. 5 for D(R) = 0 -> L (the cost of 0 -> L; L -> 0 costs its negative).
double RibbonEnergy(const Ribbon& r, const ScalpDistance& zeta, const RibbonDirectionOptions& o) {
  if (r.isocurves.empty() || r.center().empty()) return 0;
  const Eigen::Vector3f& first = r.center().front();
  const Eigen::Vector3f& last = r.center().back();
  double e = first.dot(o.down) - last.dot(o.down);
  if (zeta.available()) e += zeta(first) - zeta(last);
  return e / (2 * o.height_scale_mm);
}

// Psi: the smaller of the numbers of distinct segments on the two sides.
int LinkStrength(std::vector<int> side_a, std::vector<int> side_b) {
  const auto distinct = [](std::vector<int>* v) {
    std::sort(v->begin(), v->end());
    return static_cast<int>(std::unique(v->begin(), v->end()) - v->begin());
  };
  return std::min(distinct(&side_a), distinct(&side_b));
}

bool ValidLink(const RibbonLink& link, size_t ribbons) {
  const auto in_range = [&](int r) { return r >= 0 && static_cast<size_t>(r) < ribbons; };
  return in_range(link.ribbon[0]) && in_range(link.ribbon[1]) && link.ribbon[0] != link.ribbon[1];
}

// E_link (Eq. 6) for every pair of linked ribbons.
void AddLinkTerms(const std::vector<RibbonLink>& links, size_t ribbons, double alpha,
                  std::vector<BinaryMrfPair>* pairs) {
  struct Entry {
    uint32_t a, b;
    bool needs_equal;
    int segment_a, segment_b;
  };
  std::vector<Entry> entries;
  for (const RibbonLink& link : links) {
    if (!ValidLink(link, ribbons)) continue;
    const bool swap = link.ribbon[0] > link.ribbon[1];
    entries.push_back({static_cast<uint32_t>(link.ribbon[swap ? 1 : 0]),
                       static_cast<uint32_t>(link.ribbon[swap ? 0 : 1]), NeedsEqualDirections(link),
                       link.segment[swap ? 1 : 0], link.segment[swap ? 0 : 1]});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return std::tie(x.a, x.b, x.needs_equal) < std::tie(y.a, y.b, y.needs_equal);
  });
  // Per ribbon pair, Psi of the links that equal and that different directions would break.
  std::vector<BinaryMrfPair> strengths;
  for (size_t k = 0; k < entries.size();) {
    BinaryMrfPair pair{entries[k].a, entries[k].b, 0, 0};
    while (k < entries.size() && entries[k].a == pair.a && entries[k].b == pair.b) {
      const bool needs_equal = entries[k].needs_equal;
      std::vector<int> side_a, side_b;
      for (; k < entries.size() && entries[k].a == pair.a && entries[k].b == pair.b &&
             entries[k].needs_equal == needs_equal;
           ++k) {
        side_a.push_back(entries[k].segment_a);
        side_b.push_back(entries[k].segment_b);
      }
      (needs_equal ? pair.cost_differ : pair.cost_equal) = LinkStrength(side_a, side_b);
    }
    strengths.push_back(pair);
  }
  double largest = 0;
  for (const BinaryMrfPair& p : strengths)
    largest = std::max({largest, p.cost_equal, p.cost_differ});
  if (largest <= 0) return;
  for (BinaryMrfPair p : strengths) {
    p.cost_equal *= alpha / largest;
    p.cost_differ *= alpha / largest;
    pairs->push_back(p);
  }
}

PolylineVertexTable TabulateRibbons(const std::vector<const Ribbon*>& ribbons) {
  PolylineVertexTable table;
  for (const Ribbon* r : ribbons) {
    table.StartOwner();
    for (const Curve& curve : r->isocurves) table.Append(curve);
  }
  table.Close();
  return table;
}

// E_close (Eq. 7) for every pair of overlapping ribbons.
void AddCloseTerms(const std::vector<Ribbon>& ribbons, const RibbonDirectionOptions& o,
                   std::vector<BinaryMrfPair>* pairs, int64_t* count) {
  std::vector<const Ribbon*> all;
  for (const Ribbon& r : ribbons) all.push_back(&r);
  for (const OwnerOverlap& overlap :
       FindOwnerOverlaps(TabulateRibbons(all), o.overlap_mm, 1, o.threads)) {
    if (overlap.votes == 0) continue;
    const double cost = o.alpha_close * overlap.share;
    // Orientations that agree where they overlap are compatible with equal directions.
    pairs->push_back(
        {overlap.a, overlap.b, overlap.votes > 0 ? 0.0 : cost, overlap.votes > 0 ? cost : 0.0});
    ++*count;
  }
}

// One term per ribbon pair: the terms of each pair summed.
void MergeTerms(std::vector<BinaryMrfPair>* pairs) {
  std::sort(pairs->begin(), pairs->end(), [](const BinaryMrfPair& x, const BinaryMrfPair& y) {
    return std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  size_t out = 0;
  for (size_t k = 0; k < pairs->size(); ++k) {
    BinaryMrfPair& last = (*pairs)[out == 0 ? 0 : out - 1];
    if (out > 0 && last.a == (*pairs)[k].a && last.b == (*pairs)[k].b) {
      last.cost_equal += (*pairs)[k].cost_equal;
      last.cost_differ += (*pairs)[k].cost_differ;
    } else {
      (*pairs)[out++] = (*pairs)[k];
    }
  }
  pairs->resize(out);
}

// Reverses the l direction of the ribbons labelled 1 and the parameters of
// the links at them.
void ReverseRibbons(const std::vector<uint8_t>& reverse, std::vector<Ribbon>* ribbons,
                    std::vector<RibbonLink>* links) {
  for (size_t r = 0; r < ribbons->size(); ++r) {
    if (!reverse[r]) continue;
    for (Curve& curve : (*ribbons)[r].isocurves) std::reverse(curve.begin(), curve.end());
  }
  for (RibbonLink& link : *links) {
    if (!ValidLink(link, ribbons->size())) continue;
    for (int k = 0; k < 2; ++k) {
      const size_t r = static_cast<size_t>(link.ribbon[k]);
      if (!reverse[r]) continue;
      link.link_point[k].l = static_cast<float>((*ribbons)[r].length()) - link.link_point[k].l;
      link.link_point[k].orientation = -link.link_point[k].orientation;
      link.segment_along_ribbon[k] = !link.segment_along_ribbon[k];
    }
  }
}

}  // namespace

double RibbonOverlap(const Ribbon& a, const Ribbon& b, double overlap_mm, bool* compatible) {
  if (compatible != nullptr) *compatible = true;
  if (!(overlap_mm > 0)) return 0;
  const std::vector<OwnerOverlap> overlaps =
      FindOwnerOverlaps(TabulateRibbons({&a, &b}), overlap_mm, 1, 1);
  if (overlaps.empty()) return 0;
  if (compatible != nullptr) *compatible = overlaps[0].votes >= 0;
  return overlaps[0].share;
}

Status RibbonDirectionOptions::Check() const {
  if (!(height_scale_mm > 0))
    return InvalidArgument("ribbon direction height_scale_mm must be positive");
  if (!(alpha_link >= 0) || !(alpha_close >= 0))
    return InvalidArgument("ribbon direction weights must be non-negative");
  if (!(overlap_mm > 0)) return InvalidArgument("ribbon direction overlap_mm must be positive");
  if (threads < 1) return InvalidArgument("ribbon direction threads must be at least 1");
  if (!(std::abs(down.norm() - 1) < 1e-3))
    return InvalidArgument("ribbon direction down must be a unit vector");
  return Status::Ok();
}

RibbonDirectionSummary DirectRibbons(std::vector<Ribbon>* ribbons, std::vector<RibbonLink>* links,
                                     const HeadModel* head, const RibbonDirectionOptions& options) {
  RibbonDirectionSummary summary;
  const size_t n = ribbons->size();
  summary.ribbons = static_cast<int64_t>(n);
  summary.links = static_cast<int64_t>(links->size());
  if (n == 0) return summary;

  // Label 0: D(R) = 0 -> L; label 1: L -> 0.
  BinaryMrf mrf;
  const ScalpDistance zeta(head);
  for (const Ribbon& r : *ribbons) {
    const double keep = RibbonEnergy(r, zeta, options);
    mrf.unary.push_back({keep, -keep});
  }
  AddLinkTerms(*links, n, options.alpha_link, &mrf.pairs);
  AddCloseTerms(*ribbons, options, &mrf.pairs, &summary.overlapping_pairs);
  MergeTerms(&mrf.pairs);
  const BinaryMrfSolution solution = SolveBinaryMrf(mrf);
  summary.energy = solution.energy;
  summary.truncated_pairs = solution.truncated_pairs;

  ReverseRibbons(solution.labels, ribbons, links);
  summary.reversed = std::count(solution.labels.begin(), solution.labels.end(), 1);
  // Every ribbon now runs 0 -> L: a link is compatible when it needs equal directions.
  const auto incompatible = [n](const RibbonLink& link) {
    return !ValidLink(link, n) || !NeedsEqualDirections(link);
  };
  summary.incompatible_links = std::count_if(links->begin(), links->end(), incompatible);
  summary.compatible_links = summary.links - summary.incompatible_links;
  links->erase(std::remove_if(links->begin(), links->end(), incompatible), links->end());
  return summary;
}

}  // namespace hairrig
