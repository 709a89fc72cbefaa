// Where the views see strands end (mm, the points' frame).
//
// Bao & Qi 2017 end a grown strand only where it leaves the hair volume or
// reaches the maximum length (Sec. IV-B, I_bound); a strand that follows a
// seen strand to its end then carries on along the field, under the hair
// beside it, to the volume's edge. Where a seen strand's tip end lies on the
// hair's surface and no other seen strand carries on from it, the views saw
// that strand end there more often than not, if the seen strand is long: on
// the simulated rig's default scene, of the tip ends of seen strands 40 mm
// long or more that no other seen strand continues, 86 % lie within 5 mm of
// a true strand's tip (56 % on the same scene as a photograph, 40 % path
// traced; 90, 63 and 46 % once the points' test below drops more), against 3 %
// of the seen strands' middle vertices
// (`bench/seen_tip_truth.py`; docs/accuracy.md, "Where strands end").
//
// SeenTips::Find keeps the tip ends of the directed segments (root to tip,
// strand_direction.h) at least min_seen_length_mm long that no other segment
// continues: no vertex of another
// segment lies ahead_min_mm..ahead_max_mm ahead of the tip along its
// tangent, within lateral_mm of that line, with its tangent within
// max_angle_deg of the tip's (either sense: the direction MRF may have
// turned the continuing segment the other way), on a segment that reaches
// carry_on_mm or more ahead of the tip. A segment's own vertices do not
// continue it. Given the oriented points, a tip they run on past is dropped
// too (points_ahead_max_share). Strand growth (strand_growth.h) ends a strand that, while
// following a seen strand, comes within reach_mm of such a tip in about its
// direction, except where the hair is seen to curl (curl_field.h): on
// curly_blond 31 % of the uncontinued tip ends lie at a true tip, the rest
// mostly where a curl turns out of sight. Not in Bao & Qi; `enabled = false` is the
// paper's growth.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/status.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

struct SeenTipOptions {
  bool enabled = true;
  // Only the tips of seen strands at least this long (arc length): on images
  // unlike the simulated rig's the seen strands break into short pieces whose
  // ends are mostly not the hair's (docs/accuracy.md, "Where strands end").
  double min_seen_length_mm = 40;
  // A strand shorter than this does not end at a seen tip (a seen tip at the
  // scalp is a seen strand directed into it).
  double min_strand_mm = 5;
  double ahead_min_mm = 1, ahead_max_mm = 9;  // where a continuing vertex lies, along the tangent
  double lateral_mm = 2;                      // ... and how far off the tangent's line at most
  double max_angle_deg = 45;                  // its tangent this close to the tip's, either sense
  // ... on a segment that reaches at least this far ahead of the tip (along
  // the tip's tangent): a neighbour that ends beside the tip, as the strands
  // of one lock do, does not carry the hair on past it (0: any vertex in the
  // window continues the tip, which keeps a quarter to a half as many tips).
  double carry_on_mm = 12;
  // Where the hair ends, so do its oriented points: a tip is kept only where
  // the points ahead of it (points_window_mm along its tangent, after
  // points_gap_mm, within points_lateral_mm of its line and points_angle_deg
  // of its direction, either sense) are none, or number under
  // points_ahead_max_share of those as far behind it. On images unlike the simulated rig's the seen
  // strands break where the hair does not end, and the points carry on past
  // the break (docs/accuracy.md, "Where strands end"). 0: the points are not
  // asked (nor are they when Find is given none).
  double points_ahead_max_share = 0.08;
  double points_gap_mm = 2, points_window_mm = 10;
  double points_lateral_mm = 3, points_angle_deg = 30;
  double reach_mm = 1.5;  // a strand this close to a seen tip has reached it
  Status Check() const;
};

class SeenTips {
 public:
  SeenTips();  // none: Reached is always false
  ~SeenTips();
  SeenTips(SeenTips&&) noexcept;
  SeenTips& operator=(SeenTips&&) noexcept;

  // The uncontinued tip ends of `segments` (none when options.enabled is
  // false); with `points` (the oriented points the segments were grown
  // from, in their frame, mm; may be null), only those the points do not run
  // on past.
  // O(vertices + points) to index, then a few radius queries per segment.
  static SeenTips Find(const std::vector<StrandSegment>& segments, const SeenTipOptions& options,
                       const std::vector<OrientedPoint>* points = nullptr);

  // Whether a strand at p growing along `direction` (unit) has reached a
  // seen tip: one lies within reach_mm of p, its tangent within 60 deg of
  // `direction`. Thread-safe.
  bool Reached(const Eigen::Vector3f& p, const Eigen::Vector3f& direction) const;

  size_t size() const;
  // Of the segments' tip ends, how many were kept as seen tips (size()) and
  // how many were looked at (segments with at least 2 vertices).
  size_t examined() const { return examined_; }

 private:
  struct Index;
  std::shared_ptr<const Index> index_;
  size_t examined_ = 0;
};

}  // namespace hairrig
