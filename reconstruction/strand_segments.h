// Strand segments grown through the oriented point cloud (Luo et al. 2013,
// Sec. 4 Eq. 2 and Sec. 5.1): the first structure the strand stage finds.
//
// A segment is a polyline (mm, the points' frame) that follows the 3D
// orientation field of the points and stays on their point set surface.
// Segments are unsigned: which end is the root is decided later
// (strand_direction.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "reconstruction/mls.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/point_orientation_field.h"

namespace hairrig {

struct SegmentGrowthOptions {
  double step_mm = 2.0;       // delta: the forward Euler step
  double sigma_mm = 2.0;      // sigma_d of Eq. 2 and the MLS projection's sigma
  double min_turn_cos = 0.9;  // T_t: stop where the next direction turns further (rule 1)
  int min_neighbours = 5;     // T_N: stop in holes and past the boundary (rule 2)
  double max_mls_along =
      0.5;  // T_MLS: stop where the MLS projection moves along the strand (rule 3)
  // Rule 3 looks only at projections that move the vertex further than this
  // (0: the paper's rule, which a noisy cloud trips on sub-0.1 mm shifts).
  double mls_min_shift_mm = 0.3;
  double neighbour_cos = 0.5;  // T_o: neighbours whose direction is this compatible with the growth
  double cover_mm = 1.5;       // Delta: seeds this close to a grown segment are covered
  // Eq. 3's weights: position, orientation, curvature. Position and
  // orientation are the paper's (for mm); its curvature weight is 5 (Sec. 8:
  // 30 for straight hair, against PMVS's noise). On the fused points here 5
  // straightens curls to a fifth of their curvature, so the default is 0.5
  // (docs/accuracy.md, "Options of the strand stage").
  double smooth_position = 0.1, smooth_orientation = 1.0, smooth_curvature = 0.5;
  double split_height_mm = 50;  // T_H: the plausibility check's height between turning points
  Eigen::Vector3f down{0, 0,
                       -1};  // d_down (unit): the reference down direction (the turntable's -z)
  int max_steps = 400;       // per growing direction
  int min_vertices = 3;      // shorter segments are dropped (their seeds stay covered)
  int threads = 2;           // segments grown at once; the result does not depend on it

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct StrandSegment {
  std::vector<Eigen::Vector3f> points_mm;  // at least min_vertices, about step_mm apart
  double Length() const;
};

struct SegmentGrowthSummary {
  int64_t seeds = 0, seeds_grown = 0;  // all points; those a segment was grown from
  int64_t segments = 0, vertices = 0;
  int64_t splits = 0;                                                       // plausibility splits
  int64_t stops_turn = 0, stops_hole = 0, stops_mls = 0, stops_length = 0;  // why growing ended
  double mean_length_mm = 0;
};

// Luo Sec. 5.1: seeds are all points, most confident first; from each
// uncovered seed a segment is grown both ways (Euler steps along Eq. 2's
// orientation, MLS-projected onto the point set surface, ended by rules
// 1-3), smoothed by Eq. 3, split where the plausibility check finds a
// U-turn, and the seeds within cover_mm of it are covered. Deterministic:
// the seeds are taken in order, whatever options.threads.
std::vector<StrandSegment> GrowStrandSegments(const std::vector<OrientedPoint>& points,
                                              const SegmentGrowthOptions& options,
                                              SegmentGrowthSummary* summary = nullptr);

// Eq. 3: positions minimising alpha0 |p - p0|^2 + alpha1 |p_{i+1} - p_i -
// t_i l_i|^2 + alpha2 |p_{i-1} - 2 p_i + p_{i+1}|^2, with t_i the unit
// direction and l_i the length of the initial edge i (the paper's t delta,
// with the edge's own length so the polyline keeps its length). Polylines of
// fewer than 3 points are returned unchanged.
std::vector<Eigen::Vector3f> SmoothPolyline(const std::vector<Eigen::Vector3f>& points,
                                            double alpha_position, double alpha_orientation,
                                            double alpha_curvature);

// The general form of Eq. 3 behind SmoothPolyline, for the variants Luo uses
// later: transitions between ribbons whose orientation term follows the
// orientation field and whose ends stay put (Sec. 6.3), and interior strands
// with the interior term of Eq. 13 (Sec. 7.1).
struct PolylineSmoothing {
  double alpha_position = 0.1, alpha_orientation = 1.0, alpha_curvature = 5.0;  // Eq. 3's weights
  // The orientation term's target edges t_i delta (mm), one per edge (n - 1
  // of them); empty: the initial edges, as SmoothPolyline.
  std::vector<Eigen::Vector3f> edges;
  // Per vertex, non-zero to keep it at its initial position; empty: none kept.
  std::vector<uint8_t> fixed;
};

// weight (gradient . p_vertex - target)^2: a scalar field's term linearised
// at a vertex (Eq. 13's alpha_int B (i / N - I(p_i))^2 is one per vertex).
struct VertexFieldTerm {
  int vertex = 0;
  Eigen::Vector3f gradient = Eigen::Vector3f::Zero();  // per mm
  double target = 0;
  double weight = 0;
};

// Minimises Eq. 3 with `smoothing`'s edges and fixed vertices plus the field
// terms (which couple x, y and z; without them the three coordinates share
// one banded system). Polylines of fewer than 3 points, and any whose system
// cannot be factored, are returned unchanged; `edges` or `fixed` of another
// size than n - 1 or n count as empty.
std::vector<Eigen::Vector3f> SmoothPolyline(const std::vector<Eigen::Vector3f>& points,
                                            const PolylineSmoothing& smoothing,
                                            const std::vector<VertexFieldTerm>& field_terms = {});

// The plausibility check: heights H = p . down; the turning points are the
// local extrema of H (with 1 mm hysteresis) and the ends; the polyline is cut
// at every turning point next to a rise or fall larger than split_height_mm.
std::vector<std::vector<Eigen::Vector3f>> SplitImplausible(
    const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& down,
    double split_height_mm);

}  // namespace hairrig
