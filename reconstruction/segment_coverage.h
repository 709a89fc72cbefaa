// Which stretches of the seen strand segments a set of strands runs along
// (mm, the points' frame). A segment vertex is covered where a strand vertex
// lies within radius_mm of it and the strand's tangent there is within
// max_angle_deg of the segment's, both directed root to tip (tangents by
// central differences along each polyline, one-sided at its ends). Strand
// growth uses it to find the seen strands that no strand grown from the scalp
// passes along (strand_growth.h, SegmentCoverOptions).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/strands.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

struct CoverageOptions {
  double radius_mm = 1.5;
  double max_angle_deg = 30;
};

class StrandCoverage {
 public:
  explicit StrandCoverage(const CoverageOptions& options);

  // Adds every strand of `strands` / one polyline (root first). Not safe
  // while another thread reads.
  void Add(const StrandSet& strands);
  void Add(const std::vector<Eigen::Vector3f>& strand);

  // A strand added so far passes p in about the direction `tangent` (unit).
  bool Covers(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent) const;

  // A vertex of an added strand: the strand's place in the order of Add
  // (a StrandSet's strands in its order), the vertex's in the strand.
  struct Vertex {
    int64_t strand = -1;
    int vertex = -1;
  };
  // The added strands' vertex nearest p within `radius_mm` whose tangent
  // lies within acos(min_cos) of `tangent`; strand -1 when there is none.
  Vertex Nearest(const Eigen::Vector3f& p, const Eigen::Vector3f& tangent, double radius_mm,
                 double min_cos) const;
  // The length (mm) of the segment's edges with an uncovered end vertex,
  // halved per uncovered end: the segment's whole length when nothing covers
  // it, 0 when everything does.
  double UncoveredLengthMm(const StrandSegment& segment) const;

 private:
  struct Entry {
    Eigen::Vector3f position, tangent;
    Vertex where;
  };
  // Calls visit(entry) for the entries in the cells within radius_mm of p,
  // until it returns true.
  template <typename Visit>
  void ForEachNear(const Eigen::Vector3f& p, double radius_mm, Visit&& visit) const;
  void Add(const Eigen::Vector3f* points, size_t count);
  int64_t CellKey(const Eigen::Vector3f& p) const;

  double radius_mm_, min_cos_;
  int64_t strands_ = 0;
  std::unordered_map<int64_t, std::vector<Entry>> cells_;
};

// The unit tangent at vertex i of the polyline points[0..count) (central
// difference, one-sided at the ends; zero for a single vertex).
Eigen::Vector3f PolylineTangent(const Eigen::Vector3f* points, size_t count, size_t i);

}  // namespace hairrig
