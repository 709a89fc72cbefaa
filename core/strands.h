// Hair strands: polylines from root to tip, millimetres, in the frame the file
// or the producer states (the world frame of the rig for captures and scenes).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// The largest coordinate a strand point may have (mm, 1000 km): within it the
// differences and squared distances of points stay finite in float arithmetic.
inline constexpr float kMaxStrandCoordinateMm = 1e9f;

struct StrandSet {
  // All points of all strands, strand after strand, root first.
  std::vector<Eigen::Vector3f> points_mm;
  // Number of points of each strand; sums to points_mm.size(). A strand has at
  // least one point (a strand of one point has no segment).
  std::vector<uint32_t> point_counts;
  // Optional per-point colour, 0-255 (PLY red/green/blue); empty or one per point.
  std::vector<std::array<uint8_t, 3>> colors;

  size_t num_strands() const { return point_counts.size(); }
  size_t num_points() const { return points_mm.size(); }
  // Offset of each strand's first point; size num_strands()+1.
  std::vector<size_t> Offsets() const;
  void AddStrand(const std::vector<Eigen::Vector3f>& points);
  // Counts consistent, every coordinate finite and within
  // +-kMaxStrandCoordinateMm, colours absent or one per point. CorruptData
  // names the strand and the vertex in it (0-based, in the set's order).
  Status Check() const;
  // Polyline length of every strand (mm).
  std::vector<double> StrandLengths() const;
};

}  // namespace hairrig
