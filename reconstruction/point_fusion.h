// Fusion of the per-view line depth maps (line_mvs.h) into one cloud of
// oriented points: a cell's segment is kept when other views' maps agree
// with it (their depth at its projection and their direction), the views
// that agree are recorded as the ones that see it, and points closer than a
// merge distance are merged (the most confident wins), so that the 38 views'
// overlapping maps give one surface, not 38 copies. A point's confidence is
// (1 - its cost) (1 - 2^-k), k the views besides the reference that agree:
// agreement predicts a point's error, its cost hardly does (0 for a point no
// other view confirms, kept only when min_agreeing_views is 0). After the
// merge, each direction is smoothed over its neighbours (Luo 2013 Sec. 4
// Eq. 2; FusionOptions::direction_sigma_mm).
//
// Frames and units: points in the views' object frame (the turntable frame
// for a capture), mm; directions unsigned.
#pragma once

#include <cstdint>
#include <vector>

#include "reconstruction/line_mvs.h"
#include "reconstruction/point_cloud.h"

namespace hairrig {

struct FusionOptions {
  double max_cost = 0.4;  // cells whose best hypothesis costs more are not points
  double depth_tolerance_mm =
      2.0;  // another view agrees where its depth at the projection is within this ...
  double angle_tolerance_deg = 20;  // ... and its direction within this
  int min_agreeing_views = 1;       // views besides the reference that must agree
  // Another view's map is read at the cell nearest the projection; where
  // that cell holds no depth under max_cost, the cells within this many
  // cells of it are read too and the one that agrees best counts (0: the
  // nearest alone). A thin wisp or a ringlet's end is a few pixels wide, and
  // the nearest cell of the other view's grid (every stride_px pixels) often
  // falls on the backdrop beside it. A nearest cell whose depth disagrees is
  // not passed over.
  int agreement_radius_cells = 0;
  double merge_mm = 0.5;  // points within one cell of this size are merged
  // Each consistent point's direction from the 2D orientation maps of every
  // view that agrees with it (Luo 2013 Sec. 4 Eq. 1, after Wei et al. 2005):
  // the direction closest to lying in each view's plane through its camera
  // and the orientation seen there, with the stereo's direction weighted as a
  // quarter of a view. A view whose plane is further than angle_tolerance_deg
  // from the stereo's direction is left out; with fewer than two views left
  // the stereo's direction stays. Off: on the demo capture it changes point
  // precision by under 0.01 (docs/accuracy.md).
  bool multiview_direction = false;
  // Luo 2013 Sec. 4 Eq. 2 on the merged points (point_orientation_field.h):
  // each direction replaced by the field's of this sigma (mm) over the
  // neighbours whose direction is within angle_tolerance_deg of it; 0 = off.
  double direction_sigma_mm = 2.0;  // Luo's sigma_d
  // Luo 2013 Sec. 4's MLS filtering of the merged points (reconstruction/mls.h):
  // the Gaussian's sigma in mm, 0 = off.
  double mls_sigma_mm = 0;
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct FusionSummary {
  int64_t candidates = 0;  // cells with an estimate under max_cost
  int64_t consistent = 0;  // ... that enough other views agree with
  int64_t points = 0;      // after merging
  // For the reconstruction's verdict: (candidate, other view) pairs where
  // the other view's map holds a depth under max_cost within
  // depth_tolerance_mm of the candidate's, and of those, the pairs whose
  // directions agree within angle_tolerance_deg too (where two views agree
  // on where the hair is, do they agree on its direction?); and the
  // candidates with at least one such depth pair.
  int64_t depth_pairs = 0;
  int64_t direction_pairs = 0;
  int64_t depth_confirmed = 0;
  bool mls = false;                  // the points were MLS-filtered
  bool smoothed_directions = false;  // ... and their directions smoothed by Eq. 2
};

// `views` and `maps` as given to and returned by ComputeLineDepthMaps (the
// same order). Each point's `views` holds indices into `views`, sorted.
// InvalidArgument when the sizes differ or the options are bad.
Result<std::vector<OrientedPoint>> FusePoints(const std::vector<MvsView>& views,
                                              const std::vector<LineDepthMap>& maps,
                                              const FusionOptions& options,
                                              FusionSummary* summary = nullptr);

}  // namespace hairrig
