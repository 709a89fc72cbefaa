// Ribbons: nearly parallel strand segments grouped into 2D grids of 3D
// vertices that follow the point set surface (Luo et al. 2013 Sec. 5.2), the
// links between ribbons from circular arcs fitted across segment ends
// (Sec. 6.1), and the ribbons' root-to-tip directions from the connection
// graph's MRF (Sec. 6.2). Units mm, the points' frame (the turntable frame for
// a capture of this rig).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

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

  int width() const { return static_cast<int>(isocurves.size()) - 1; }                       // W
  int length() const { return isocurves.empty() ? -1 : static_cast<int>(isocurves[0].size()) - 1; }  // L
  const std::vector<Eigen::Vector3f>& center() const { return isocurves[isocurves.size() / 2]; }  // R^{W/2}
};

// R^{-1}(p): the closest point of the tessellated ribbon and its parameters.
struct RibbonCoordinates {
  float w = 0, l = 0;                   // in [0, W] x [0, L]
  Eigen::Vector3f closest = Eigen::Vector3f::Zero();
  float distance_mm = 0;                // |p - closest|
  Eigen::Vector3f orientation = Eigen::Vector3f::Zero();  // o_R at (w, l), unit, pointing to increasing l
};
RibbonCoordinates ProjectOntoRibbon(const Ribbon& ribbon, const Eigen::Vector3f& p);

struct RibbonOptions {
  double spacing_mm = 1.5;        // Delta: the expansion offset between isocurves, and rule 2's distance
  double min_turn_cos = 0.9;      // T_t: rule 1, |o_S . o_R| below this makes a bad point
  int max_bad_points = 10;        // T_bad: a segment with fewer bad points is covered
  int max_failed_expansions = 2;  // consecutive failed expansions end a side
  double sigma_mm = 2.0;          // the MLS projection's sigma (as the segments')
  int max_width = 40;             // isocurves per ribbon, a bound on the expansion

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct RibbonSummary {
  int64_t ribbons = 0, covered_segments = 0, uncovered_segments = 0;
  double mean_width = 0, mean_length_mm = 0;
};

// Sec. 5.2: greedily from the longest uncovered segment, a ribbon is expanded
// to both sides over the point set surface (MLS-projected, smoothed by Eq. 3)
// while new segments get covered; excess outer isocurves are trimmed. Every
// segment ends in exactly one ribbon (a lone segment makes a 1-isocurve
// ribbon). Deterministic.
std::vector<Ribbon> CoverWithRibbons(const std::vector<OrientedPoint>& points,
                                     const std::vector<StrandSegment>& segments, const RibbonOptions& options,
                                     RibbonSummary* summary = nullptr);

// A link between two ribbons (Sec. 6.1): a circular arc fitted across the
// nearby ends of a segment of each.
struct RibbonLink {
  int ribbon[2] = {-1, -1};
  int segment[2] = {-1, -1};                // the fitted segments, one in each ribbon
  RibbonCoordinates link_point[2];          // l(R), l(R'): the segments' end vertices projected on their ribbons
  // Whether the fitted end is the segment's first vertex, and whether the
  // segment's vertex order agrees with its ribbon's l direction (majority of
  // its vertices): with the ribbons' directions these decide compatibility.
  bool at_first_vertex[2] = {false, false};
  bool segment_along_ribbon[2] = {true, true};
  double rms_mm = 0, radius_mm = 0;         // the arc fit
};

struct ConnectionOptions {
  double max_end_gap_mm = 30;   // segment ends this close are tried
  int fit_vertices = 10;        // K
  double max_rms_mm = 2.0;      // criterion (a)
  double max_curvature_ratio = 0.4;  // T_curv, criterion (b)
  double max_normal_angle_deg = 90;  // criterion (c)
  double max_overlap = 0.1;     // eta, criterion (d)

  Status Check() const;
};

struct ConnectionSummary {
  int64_t pairs_tried = 0, links = 0;
  int64_t rejected_rms = 0, rejected_curvature = 0, rejected_torsion = 0, rejected_overlap = 0;
};

// Sec. 6.1 over every pair of segments in different ribbons with ends within
// max_end_gap_mm: a 3D circle fitted to the K vertices nearest each end (plane
// fit, Taubin's algebraic circle, Levenberg-Marquardt on centre, normal and
// radius), kept unless criteria (a)-(d) reject it.
std::vector<RibbonLink> ConnectRibbons(const std::vector<Ribbon>& ribbons, const std::vector<StrandSegment>& segments,
                                       const ConnectionOptions& options, ConnectionSummary* summary = nullptr);

// eta(R, R') of Sec. 6.2: the share of the two ribbons' vertices within
// `overlap_mm` of a vertex of the other; *compatible (optional): whether
// their l directions agree at the majority of the overlapped vertices.
double RibbonOverlap(const Ribbon& a, const Ribbon& b, double overlap_mm, bool* compatible = nullptr);

struct RibbonDirectionOptions {
  double height_scale_mm = 100;  // h of Eq. 5
  double alpha_link = 1.0, alpha_close = 1.0;  // Eq. 4
  double overlap_mm = 1.5;       // Delta, for E_close
  Eigen::Vector3f down{0, 0, -1};

  Status Check() const;
};

struct RibbonDirectionSummary {
  int64_t ribbons = 0, links = 0, overlapping_pairs = 0, reversed = 0;
  int64_t compatible_links = 0, incompatible_links = 0;
  double energy = 0;
};

// Sec. 6.2: D(R) for every ribbon by the MRF of Eq. 4-7 (graph cuts), then
// every ribbon whose direction is L -> 0 is reversed in place (isocurves
// reversed, links' parameters and flags updated), so that afterwards
// l = 0 is the root end of every ribbon and `links` holds only the links
// compatible with the directions. `head` (may be null) gives zeta.
RibbonDirectionSummary DirectRibbons(std::vector<Ribbon>* ribbons, std::vector<RibbonLink>* links,
                                     const HeadModel* head, const RibbonDirectionOptions& options);

}  // namespace hairrig
