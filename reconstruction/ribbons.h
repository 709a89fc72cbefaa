// Ribbons: nearly parallel strand segments grouped into 2D grids of 3D
// vertices that follow the point set surface (Luo et al. 2013 Sec. 5.2), the
// links between ribbons from circular arcs fitted across segment ends
// (Sec. 6.1), and the ribbons' root-to-tip directions from the connection
// graph's MRF (Sec. 6.2). Units mm, the points' frame (the turntable frame for
// a capture of this rig).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

// A ribbon R: isocurves[j][i] is the vertex R_i^j, j = 0..W across the
// ribbon, i = 0..L along it; every isocurve has L + 1 vertices, about
// `step_mm` apart along and `spacing_mm` apart across. After DirectRibbons,
// i = 0 is the root end (D(R) = 0 -> L).
struct Ribbon {
  std::vector<std::vector<Eigen::Vector3f>> isocurves;
  std::vector<int> segments;  // the strand segments it covers (indices into the segment list)

  int width() const { return static_cast<int>(isocurves.size()) - 1; }  // W
  int length() const {
    return isocurves.empty() ? -1 : static_cast<int>(isocurves[0].size()) - 1;
  }  // L
  const std::vector<Eigen::Vector3f>& center() const {
    return isocurves[isocurves.size() / 2];
  }  // R^{W/2}
};

// R^{-1}(p): the closest point of the tessellated ribbon and its parameters.
struct RibbonCoordinates {
  float w = 0, l = 0;  // in [0, W] x [0, L]
  Eigen::Vector3f closest = Eigen::Vector3f::Zero();
  float distance_mm = 0;  // |p - closest|
  Eigen::Vector3f orientation =
      Eigen::Vector3f::Zero();  // o_R at (w, l), unit, pointing to increasing l
};
// Each grid cell (R_i^j, R_{i+1}^j, R_{i+1}^{j+1}, R_i^{j+1}) is two triangles
// split along its R_i^j - R_{i+1}^{j+1} diagonal; w, l and o_R are
// interpolated barycentrically from the corners (o_R at a vertex is Sec. 5.2's
// <R_{i+1}^j - R_{i-1}^j>, one-sided at the ends). A 1-isocurve ribbon (W = 0)
// is its polyline. Exact (every cell is tried: O(W L)). An empty ribbon gives
// distance_mm = +infinity.
RibbonCoordinates ProjectOntoRibbon(const Ribbon& ribbon, const Eigen::Vector3f& p);

struct RibbonOptions {
  double spacing_mm = 1.5;  // Delta: the expansion offset between isocurves, and rule 2's distance
  double step_mm =
      2.0;  // delta: the vertex spacing along the isocurves (the first is its segment resampled)
  double min_turn_cos = 0.9;  // T_t: rule 1, |o_S . o_R| below this makes a bad point
  int max_bad_points = 10;    // T_bad: a segment with fewer bad points is covered
  // ... and with fewer bad points than this share of its vertices: the paper's
  // T_bad alone would let a segment of under 10 vertices be covered from anywhere.
  double max_bad_fraction = 1.0 / 3;
  int max_failed_expansions = 2;  // consecutive failed expansions end a side
  double sigma_mm = 2.0;          // the MLS projection's sigma (as the segments')
  int min_neighbours =
      5;  // T_N: an isocurve vertex with fewer points within 2 sigma stays unprojected
  // Eq. 3's weights for smoothing a new isocurve (the segments' values).
  double smooth_position = 0.1, smooth_orientation = 1.0, smooth_curvature = 5.0;
  int max_width = 40;  // isocurves per ribbon, a bound on the expansion

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct RibbonSummary {
  int64_t ribbons = 0;
  // Segments sharing their ribbon with another segment, and those alone in theirs.
  int64_t covered_segments = 0, uncovered_segments = 0;
  double mean_width = 0;      // W, in isocurve spacings (spacing_mm)
  double mean_length_mm = 0;  // of the centre isocurves
};

// Sec. 5.2: greedily from the longest uncovered segment, a ribbon is expanded
// to both sides over the point set surface (MLS-projected, smoothed by Eq. 3)
// while new segments get covered; excess outer isocurves are trimmed. Every
// segment ends in exactly one ribbon (a lone segment makes a 1-isocurve
// ribbon). Segments without vertices are left out. Deterministic
// (single-threaded; the covering makes it sequential).
//
// The first expansion offsets o_R x n use the MLS normals n of the first
// isocurve (signed consistently along it); later ones use the ribbon's own
// normal n_R = o_R x (outer - inner isocurve) (the paper's n_R formula crosses
// two nearly parallel tangents), which makes the offset the outward step
// between the two outer isocurves, orthogonalised to o_R. A segment is tested
// against the whole ribbon when a vertex of the new isocurve comes near it;
// its vertices are projected onto the cells around their nearest ribbon
// vertex (found through a hash grid, or by walking the grid downhill from the
// previous vertex's), which is exact unless the grid folds sharply there.
std::vector<Ribbon> CoverWithRibbons(const std::vector<OrientedPoint>& points,
                                     const std::vector<StrandSegment>& segments,
                                     const RibbonOptions& options,
                                     RibbonSummary* summary = nullptr);

// A link between two ribbons (Sec. 6.1): a circular arc fitted across the
// nearby ends of a segment of each.
struct RibbonLink {
  int ribbon[2] = {-1, -1};
  int segment[2] = {-1, -1};  // the fitted segments, one in each ribbon
  RibbonCoordinates
      link_point[2];  // l(R), l(R'): the segments' end vertices projected on their ribbons
  // Whether the fitted end is the segment's first vertex, and whether the
  // segment's vertex order agrees with its ribbon's l direction (majority of
  // its vertices): with the ribbons' directions these decide compatibility.
  bool at_first_vertex[2] = {false, false};
  bool segment_along_ribbon[2] = {true, true};
  double rms_mm = 0, radius_mm = 0;  // the arc fit
};

struct ConnectionOptions {
  double max_end_gap_mm = 30;        // segment ends this close are tried
  int fit_vertices = 10;             // K
  double max_rms_mm = 2.0;           // criterion (a)
  double max_curvature_ratio = 0.4;  // T_curv, criterion (b)
  double max_normal_angle_deg = 90;  // criterion (c)
  double max_overlap = 0.1;          // eta, criterion (d)
  // Arcs of a larger radius count as straight: in (b) every curvature is
  // raised to at least 1 / straight_radius_mm (two straight pieces are
  // compatible, and their joint arc must be about as straight), and their
  // normals, which noise decides, are left out of (c).
  double straight_radius_mm = 1000;
  // The gap p -> p' must continue both segments: the cosine between each end's
  // outward tangent and the gap (towards the other end) above this (0: within
  // 90 deg). Not checked for ends within 0.5 mm of each other.
  double min_gap_cos = 0.0;
  int threads = 2;  // for the fits; the result does not depend on it

  Status Check() const;
};

// A rejected pair counts under the first test it fails, in the order: the gap
// direction, (b) and (c) of the two pieces alone, (a), (d), then (b) and (c)
// with the joint arc.
struct ConnectionSummary {
  int64_t pairs_tried = 0, links = 0;
  int64_t rejected_rms = 0, rejected_curvature = 0, rejected_torsion = 0, rejected_overlap = 0;
  int64_t rejected_direction = 0;  // the gap does not continue both segments (min_gap_cos)
};

// Sec. 6.1 over every pair of segments in different ribbons with ends within
// max_end_gap_mm: a 3D circle fitted to the K vertices nearest each end (plane
// fit, Taubin's algebraic circle, Levenberg-Marquardt on centre, normal and
// radius), kept unless criteria (a)-(d) or the gap's direction reject it.
// Ends of segments with fewer than 3 vertices, or in no ribbon, are not tried.
// The pieces' normals (c) are signed by the arc's traversal from S to S', so
// that their angle tells a C from an S. Deterministic. Costly where hair is
// dense: a 190,000-point capture's 20,000 segments give about 20 M pairs of
// ends and 2 M arc fits (about 25 s on one core).
std::vector<RibbonLink> ConnectRibbons(const std::vector<Ribbon>& ribbons,
                                       const std::vector<StrandSegment>& segments,
                                       const ConnectionOptions& options,
                                       ConnectionSummary* summary = nullptr);

// eta(R, R') of Sec. 6.2: the share of the two ribbons' vertices within
// `overlap_mm` of a vertex of the other; *compatible (optional): whether
// their l directions agree at the majority of the overlapped vertices (true
// on a tie or without overlap). Vertices within overlap_mm (<=) overlap; each
// vertex's o_R is compared with that of the other's nearest vertex.
double RibbonOverlap(const Ribbon& a, const Ribbon& b, double overlap_mm,
                     bool* compatible = nullptr);

struct RibbonDirectionOptions {
  double height_scale_mm = 100;                // h of Eq. 5
  double alpha_link = 1.0, alpha_close = 1.0;  // Eq. 4
  double overlap_mm = 1.5;                     // Delta, for E_close
  Eigen::Vector3f down{0, 0, -1};              // H's direction (unit)
  int threads = 2;  // for the overlap search; the result does not depend on it

  Status Check() const;
};

struct RibbonDirectionSummary {
  int64_t ribbons = 0, links = 0, overlapping_pairs = 0, reversed = 0;
  int64_t compatible_links = 0,
          incompatible_links = 0;  // with the final directions; the latter dropped
  int64_t truncated_pairs = 0;     // ribbon pairs whose terms stayed non-submodular (binary_mrf.h)
  double energy = 0;               // Eq. 4 at the solution
};

// Sec. 6.2: D(R) for every ribbon by the MRF of Eq. 4-7 (graph cuts), then
// every ribbon whose direction is L -> 0 is reversed in place (isocurves
// reversed, links' parameters and flags updated), so that afterwards
// l = 0 is the root end of every ribbon and `links` holds only the links
// compatible with the directions. `head` (may be null) gives zeta.
//
// A link is compatible when a strand can run through it: one of its pieces
// P, P' (taken from the fitted end inwards) runs with its ribbon's direction
// and the other against (Sec. 6.2). Psi of a set of links is the smaller of
// the numbers of distinct segments on either side; Eq. 6 divides by the
// largest Psi of the links between one pair of ribbons that either choice
// of their relative direction would make incompatible. Links that do not
// name two different ribbons in range are ignored and dropped.
RibbonDirectionSummary DirectRibbons(std::vector<Ribbon>* ribbons, std::vector<RibbonLink>* links,
                                     const HeadModel* head, const RibbonDirectionOptions& options);

}  // namespace hairrig
