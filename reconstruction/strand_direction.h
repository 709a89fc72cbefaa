// Which end of each strand segment is nearer the root: Luo et al. 2013
// Sec. 6.2's direction analysis as a two-label MRF over the segments, solved
// by graph cuts (Boykov-Kolmogorov max-flow, Debian's libmaxflow).
//
// Energy (Luo Eq. 4), per segment S with label D(S) (keep its vertex order as
// root to tip, or reverse it):
//   E_ribb (Eq. 5): (H(first) - H(last) + zeta(first) - zeta(last)) / (2 h),
//     H the height along `down`, zeta the distance to the scalp: hair falls
//     and leaves the scalp;
//   E_link (Eq. 6): end-to-end links between segments whose ends meet (gap
//     within link_gap_mm, tangents and gap aligned within link_cos); an
//     incompatible link costs alpha_link, shared among the links at its
//     ends (share_link_ends: a departure from the paper, whose Eq. 6
//     normalises per pair of ribbons; one strand continues into at most one
//     other, so an end's links are not independent evidence);
//   E_close (Eq. 7): segments that run side by side (vertices within
//     overlap_mm) with incompatible directions cost alpha_close times the
//     share of overlapped vertices, shared among a segment's overlaps
//     (share_overlaps: a departure from the paper, whose ribbons are few).
// The pairwise terms are made submodular by orienting the segments along a
// maximum spanning tree of the pair graph first; the few that stay
// non-submodular are truncated (Rother et al. 2005's truncation), so the cut
// is exact for the truncated energy (binary_mrf.h).
//
// Links here join segment ends directly; the circle fits of Sec. 6.1 link
// ribbons (ribbons.h), whose MRF is the same over ribbons.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

struct DirectionOptions {
  double height_scale_mm = 100;  // h of Eq. 5
  double alpha_link = 1.0;       // Eq. 4's weights
  double alpha_close = 1.0;
  double link_gap_mm = 10;  // ends this close may link
  double link_cos = 0.8;    // |tangent . tangent'| and the gap's alignment for a link
  // An end's links share alpha_link (each weighs alpha_link over the larger
  // number of links at its two ends) instead of alpha_link each. Where many
  // segments radiate from one spot (a crown whorl, a parting: roots that meet,
  // not a strand that continues), each of their links then weighs little;
  // their pull on a segment is at most one link's, so a whorl whose segments
  // fall less than h (E_ribb under alpha_link) can still be reversed.
  bool share_link_ends = true;
  double overlap_mm = 3.0;  // vertices this close overlap
  // A segment's overlaps share alpha_close: each weighs alpha_close times its
  // share divided by the larger summed share of its two segments (when that
  // exceeds 1), instead of alpha_close times its share. Where the points cover
  // the hair densely every segment overlaps hundreds of others, the pairwise
  // terms drown Eq. 5, and the few overlaps that are wrong (segments crossing
  // between layers) can reverse whole regions (docs/accuracy.md, "Strands"). A
  // departure from the paper, whose ribbons are few; `false` weighs every
  // overlap as Eq. 7.
  bool share_overlaps = true;
  // Each segment keeps only its max_overlaps strongest overlaps (largest
  // share; a pair stays when either of its segments keeps it), 0 keeps all.
  // Where the hair is dense a segment overlaps hundreds of others; the
  // strongest few carry its neighbourhood's direction, and the minimum cut
  // over all of them is the stage's largest cost (docs/accuracy.md, "Strands").
  int max_overlaps = 32;
  // Overlaps are looked for from every overlap_stride-th vertex of each
  // segment (1: every vertex, as Eq. 7 counts them; 2 halves the queries,
  // the stage's largest cost: on the simulated scenes the share of vertices
  // directed right moves by under 0.4 %, bao-qi's precision by up to 0.02).
  int overlap_stride = 2;
  Eigen::Vector3f down{0, 0, -1};  // H's direction (unit)
  int threads = 2;

  Status Check() const;
};

struct DirectionSummary {
  int64_t segments = 0, links = 0;
  // Overlapping pairs whose tangents vote one way (votes != 0); those kept
  // (max_overlaps), over which share_overlaps normalises.
  int64_t overlaps_found = 0, overlaps = 0;
  int64_t reversed = 0;             // segments whose vertex order was flipped
  int64_t truncated_pairs = 0;      // non-submodular pairs truncated
  int64_t unary_disagreements = 0;  // segments whose label goes against their own E_ribb
  // Eq. 4's truncated energy at the solution less its floor (the minimum cut;
  // BinaryMrfSolution::cut).
  double energy = 0;
};

// Reverses the segments whose root is at their last vertex, so every
// segment runs root to tip. `head` (may be null) gives zeta; without it
// E_ribb uses the height alone.
DirectionSummary DirectSegments(std::vector<StrandSegment>* segments, const HeadModel* head,
                                const DirectionOptions& options);

}  // namespace hairrig
