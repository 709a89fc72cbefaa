// Side-by-side polylines: which owners (a strand segment, a ribbon with all
// its isocurves) have vertices within a distance of each other's, and whether
// their tangents agree there. The overlap eta and the direction compatibility
// of Luo et al. 2013 Sec. 6.2 (Eq. 7), shared by the segment and the ribbon
// direction MRFs. Units mm, any frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace hairrig {

// The unit tangent of a polyline at vertex i: <p[i+1] - p[i-1]> (one-sided at
// the ends); zero where the two vertices coincide.
Eigen::Vector3f PolylineTangent(const std::vector<Eigen::Vector3f>& points, size_t i);

// The vertices of many polylines in one table, each with its tangent and
// owner. Owners are numbered 0, 1, ... in the order they are started; an
// owner may hold several polylines (a ribbon's isocurves).
struct PolylineVertexTable {
  std::vector<Eigen::Vector3f> positions, tangents;
  std::vector<uint32_t> owner;
  std::vector<uint32_t> first;  // per owner, its first row; after Close, one past the end last

  void StartOwner() { first.push_back(static_cast<uint32_t>(positions.size())); }
  void Append(const std::vector<Eigen::Vector3f>& polyline);  // to the last started owner
  void Close() { first.push_back(static_cast<uint32_t>(positions.size())); }
  size_t owners() const { return first.empty() ? 0 : first.size() - 1; }  // once closed
  uint32_t vertices(uint32_t o) const { return first[o + 1] - first[o]; }
};

// One table of every polyline, one owner each.
PolylineVertexTable TabulatePolylines(
    const std::vector<const std::vector<Eigen::Vector3f>*>& polylines);

struct OwnerOverlap {
  uint32_t a = 0, b = 0;  // the owners, a < b
  // Queried vertices of either owner with a vertex of the other within
  // reach, and their tangents' vote against the other's nearest vertex
  // there: +1 where they agree (dot >= 0), -1 where they oppose.
  int overlapped = 0, votes = 0;
  double share = 0;  // eta: overlapped / (queried vertices of a and of b)
};

// Every pair of owners of a closed table with vertices within overlap_mm
// (<=) of each other's, sorted by (a, b). Every `stride`-th vertex of each
// owner is queried (1: every vertex). Work is spread over `threads`; the
// result does not depend on it.
std::vector<OwnerOverlap> FindOwnerOverlaps(const PolylineVertexTable& table, double overlap_mm,
                                            int stride, int threads);

// Keeps the overlaps among the `keep` largest shares of either of their
// owners (a pair stays when one of its two keeps it; equal shares are ranked
// by their order in *overlaps), in their order. `owners` bounds every a and b.
void KeepStrongestOverlaps(size_t owners, int keep, std::vector<OwnerOverlap>* overlaps);

}  // namespace hairrig
