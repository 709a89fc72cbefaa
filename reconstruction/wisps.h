// Wisps and the strands synthesised from them (Luo et al. 2013 Sec. 6.3 and
// Sec. 7): directed ribbons (ribbons.h) connected up through their
// compatible links into wisps, wisps attached to the scalp through interior
// strands regularised by the interior field, interior wisps filling the
// occluded volume, and strands synthesised within each wisp's ranges. Units
// mm, the points' frame (the turntable frame for a capture of this rig).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "core/strands.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/ribbons.h"

namespace hairrig {

// A wisp: a ribbon-like grid (isocurves[j][i], j across, i from the root on
// the scalp to the tip), with the ranges g-(l), g+(l) of Eq. 14.
struct Wisp {
  std::vector<std::vector<Eigen::Vector3f>> isocurves;
  std::vector<float> range_low, range_high;  // per i, in [0, W]
  bool interior = false;                     // Sec. 7.2 (no data points)
  bool attached = false;                     // rooted on the scalp (Sec. 7.1)
  // Per i: the unit normal at the centre isocurve, (R^{c+1}_i - R^{c-1}_i) x
  // (R^c_{i+1} - R^c_{i-1}) signed to point away from the head (the paper's
  // n_R crosses two differences along l, which are parallel). Synthesised
  // strands are thickened against it, into the hair volume.
  std::vector<Eigen::Vector3f> normals;
  // The first vertices of every isocurve that are the interior strand from
  // the root (Sec. 7.1; the root and the attaching point R_0 included; 0
  // when not attached). An interior wisp is all interior strand.
  int interior_vertices = 0;
  // The ribbons connected into it (indices into BuildWisps' `ribbons`), from
  // the one it started from (the tip's) up to the root's; empty for interior wisps.
  std::vector<int> ribbons;

  int width() const { return static_cast<int>(isocurves.size()) - 1; }  // W
  int length() const {
    return isocurves.empty() ? -1 : static_cast<int>(isocurves[0].size()) - 1;
  }  // L
  const std::vector<Eigen::Vector3f>& center() const { return isocurves[isocurves.size() / 2]; }
};

struct WispOptions {
  double link_distance_mm = 10;  // sigma_l: a feasible link's distance to R_0^{W/2} (Sec. 6.3)
  double max_connect_overlap =
      0.1;                         // connections to ribbons overlapping more than this are refused
  double overlap_mm = 1.5;         // Delta (as RibbonDirectionOptions')
  double step_mm = 2.0;            // delta: the transition's and interior strands' discretisation
  double bridge_sigma_mm = 6.0;    // the larger sigma_d of the transitions' orientation
  double interior_weight = 0.005;  // alpha_int of Eq. 13
  double voxel_mm = 4.0;           // the interior field's grid
  double interior_min_scalp_distance_mm = 20;  // Sec. 7.2's sampling threshold
  int interior_wisps = 200;                    // how many interior wisps to generate
  int interior_width = 4;                      // their width W (W + 1 isocurves)
  double taper_start = 0.7;  // share of the length where the ranges start to taper (Sec. 7.3)
  Eigen::Vector3f down{
      0, 0, -1};  // unit; without a parting, d_s leads away from the crown above the scalp centre
  uint64_t seed = 1;  // root and interior point draws

  // Delta: the interior wisps' isocurve spacing, and how close a point must
  // lie to a wisp to cover it (Eq. 14's ranges).
  double spacing_mm = 1.5;
  double cover_cos = 0.9;  // and how well its direction must agree (|o_p . o_R|, as T_t)
  // Eq. 3's weights for the transitions and interior strands (the paper's, for mm).
  double smooth_position = 0.1, smooth_orientation = 1.0, smooth_curvature = 5.0;
  double head_clearance_mm =
      1.0;  // interior strands' vertices (but the root) stay this far outside the head
  double root_jitter_mm = 3.0;  // the neighbourhood of p_k the root r is drawn from (Sec. 7.1)
  // The wisp's width at its root, as a share of its width at the attaching
  // point: the other isocurves' offsets from the centre grow linearly along
  // the interior strand from this share to 1.
  double root_width_share = 0.3;
  double interior_truncate_level =
      0.8;                       // interior wisps end where the interior field first exceeds this
  double range_smoothness = 10;  // lambda of the ranges' smoothing (per squared vertex step)
  double tip_range_share =
      0.2;  // the ranges' width at the tip, as a share of their untapered width
  // A lone ribbon (no connection) covering at least this many segments is
  // kept as a wisp; 0: every lone ribbon is removed as an outlier (the paper).
  int keep_lone_ribbon_segments = 0;
  // Connecting up must lead towards the root: a predecessor's root end must
  // rank lower than the wisp's current start by H + zeta (height along
  // `down` plus the distance to the scalp, the quantity of Eq. 5) by at least
  // this much (mm). Negative: off (the paper, which lets chains of links wander
  // down and up again across neighbouring strands).
  double min_progress_mm = 0;

  Status Check() const;
};

struct WispSummary {
  int64_t wisps = 0, connections = 0, removed_covered = 0, removed_outliers = 0;
  int64_t attached = 0, interior = 0;
  int64_t unattached = 0;      // wisps dropped unattached (no vertex, or a non-finite R_0)
  int64_t covered_points = 0;  // points that set some wisp's ranges
  double mean_length_mm = 0;   // of the centre isocurves, interior strands included
};

// Sec. 6.3, 7.1, 7.2 and 7.3's ranges. `ribbons` run root to tip and `links`
// are the compatible ones (DirectRibbons).
//  - Connecting up: every ribbon with at least two vertices along starts a
//    wisp. From the beginning of the wisp's current ribbon C, the feasible
//    links lie within sigma_l of C^{w_c}_0 (w_c: the wisp's centre isocurve
//    mapped into C's width) and enter C at the root-ward end of their
//    segment; the predecessor R* maximises Psi (Eq. 8) among the ribbons not
//    yet in the wisp that overlap C by at most max_connect_overlap; the link
//    of least distortion (Eq. 10, over the span of the wisp's isocurves in C)
//    gives the stitching map (Eq. 9). C is kept from its link point to where
//    the wisp left it, R* up to its link point, and between them runs a
//    transition at step_mm, smoothed by Eq. 3 with both ends and their
//    neighbours fixed and the orientation term from the points' orientation
//    at bridge_sigma_mm (sampled along the centre isocurve's transition,
//    shared by all isocurves). Without a direct predecessor, links entering
//    a ribbon that overlaps C with a compatible direction serve, their link
//    point projected onto C.
//  - Removal: a wisp of one ribbon that no connection touched is an outlier;
//    a wisp whose every vertex lies within overlap_mm of a vertex of another
//    remaining wisp is covered (checked from the smallest wisp up).
//  - Attachment (Sec. 7.1, scalp_guide.h): the root r and d_g for q = the
//    centre's R_0 (Eq. 11-12); the interior strand r, r + delta d_g,
//    r + 2 delta d_g (kept), then straight to q (kept) at step_mm, pushed
//    out of the head, smoothed (with the wisp's R_1 kept after q, so that
//    it runs into the wisp without a kink) by Eq. 3 plus Eq. 13's interior term
//    (linearised, three Gauss-Newton rounds; B the points' bounding box
//    diagonal) and kept head_clearance_mm outside the head. The other
//    isocurves get it offset by their offset from the centre at R_0 times a
//    share growing from root_width_share at the root to 1, their roots moved
//    onto the head's surface.
//  - Interior wisps (Sec. 7.2): interior_wisps points drawn (seeded) among
//    those farther than interior_min_scalp_distance_mm from every scalp
//    sample, each given an interior strand cut where the interior field
//    first exceeds interior_truncate_level, expanded to interior_width + 1
//    isocurves spacing_mm apart across grad I x tangent.
//  - Ranges (Eq. 14): a point covers a wisp when it lies within spacing_mm
//    of its surface with |o_p . o_R| >= cover_cos; the bounds per vertex
//    along are smoothed (first differences, range_smoothness, which also
//    fills vertices no point covers), [0, W] without any covered point and
//    for interior wisps, then tapered quadratically from taper_start of the
//    length to tip_range_share at the tip.
// Deterministic for options.seed. InvalidArgument for bad options, no
// points, a ribbon whose isocurves differ in length, a link naming a ribbon
// that does not exist, a head without scalp, or when no wisp is left.
Result<std::vector<Wisp>> BuildWisps(const std::vector<OrientedPoint>& points,
                                     const std::vector<Ribbon>& ribbons,
                                     const std::vector<RibbonLink>& links, const HeadModel& head,
                                     const WispOptions& options, WispSummary* summary = nullptr);

// Eq. 14's ranges (the rules in BuildWisps' comment): from the points for
// every wisp that is not interior, [0, W] for interior ones, all tapered.
// Overwrites range_low and range_high; returns how many points cover some
// wisp.
int64_t SetWispRanges(const std::vector<OrientedPoint>& points, const WispOptions& options,
                      std::vector<Wisp>* wisps);

struct SynthesisOptions {
  double thickness_mm = 3.0;  // T_thick: strands are offset against the wisp's normal by up to this
  double thickness_ramp_mm =
      10;  // the offset grows from 0 at the root over this much of the strand
  // Eq. 3's weights for the final smoothing (the paper's, for mm).
  double smooth_position = 0.1, smooth_orientation = 1.0, smooth_curvature = 5.0;

  Status Check() const;
};

// Sec. 7.3: `strands` strands spread over the wisps in proportion to their
// ranges' width (in isocurves, plus one) times their length (mm), each at
// t in [0, 1] (stratified over the wisp's strands) with the width
// parameter g(l, t) = g-(l) (1 - t) + g+(l) t, offset against the wisp's
// normal by a random share of T_thick, smoothed by Eq. 3 with the root kept.
// The count is given instead of the paper's T_density iteration. Root to
// tip, mm, the wisps' frame. Wisps of fewer than two vertices get
// none; no wisp: no strand. Deterministic for a seed.
StrandSet SynthesizeStrands(const std::vector<Wisp>& wisps, int strands, uint64_t seed,
                            const SynthesisOptions& options = SynthesisOptions{});

}  // namespace hairrig
