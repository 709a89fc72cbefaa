// Full strands grown from roots on the scalp (mm, the points' frame):
//   - Bao & Qi 2017 Sec. IV-B: p_i = p_{i-1} + delta H(p_{i-1}) (Eq. 2) in the
//     hybrid field H = a_s S_s + a_i V_i + a_d grad I_d + a_g O_g (Eq. 1), with
//     the paper's dynamic weights from d_s, the distance to the ribbons:
//       d_s < T_s:  a_s = 100 - d_s, a_i = 0.1, a_d = 0.1 a_i, a_g = 10
//       else:       a_s = 0, a_i = 100 d_s, a_d = 0.1 a_i, a_g = 10
//     H is normalised before the step (the weights scale it by up to 100 d_s,
//     which would make the step length arbitrary), and the distance term
//     descends I_d (-grad I_d), which keeps strands in the hair volume (the
//     paper's sign would push them out of it). Growth stops where I_d exceeds
//     I_bound or at the maximum length, and (StrandGrowthOptions::
//     max_off_hair_mm) where the hair the cameras saw ends: I_d's Laplace
//     solve stays low over a head covered in hair, so a strand that has run
//     past the end of short hair would go on along its surface. Beside Eq. 1's
//     terms, H follows the nearest seen strand (follow_radius_mm), and past
//     the seen strands a curly strand goes on as a helix about H
//     (helix_continuation.h). Where the
//     views are given (SkinViews), a strand also ends where it runs in front
//     of skin the cameras see (skin_views.h): bangs and strands past the
//     hair's end would otherwise slide down over the face and neck, where
//     I_d, fed by the seen segments alone, does not stop them.
//   - the naive baseline: the direction of the nearest points (Luo Eq. 2
//     over the oriented points within 2 sigma of the field, signed to
//     continue the strand), no structure
//     analysis; straight out of the scalp until the strand reaches points,
//     stopped where it leaves them.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/head_model.h"
#include "core/status.h"
#include "core/strands.h"
#include "reconstruction/curl_field.h"
#include "reconstruction/free_space.h"
#include "reconstruction/helix_continuation.h"
#include "reconstruction/hybrid_field.h"
#include "reconstruction/seen_tips.h"
#include "reconstruction/segment_coverage.h"
#include "reconstruction/skin_views.h"
#include "reconstruction/strand_segments.h"
#include "reconstruction/voxel_cache.h"

namespace hairrig {

// The direction a strand leaves the scalp in, at a scalp point with outward
// unit `normal`: the normal tilted towards `down` (unit; the points' frame's
// down, -z in the turntable frame, DirectionOptions::down) along the scalp,
// sin(e) n + cos(e) g normalised, with g the part of `down` tangent to the
// scalp (|g| = 1 where the scalp is vertical, 0 at the crown and under the
// chin). `elevation_deg` e in (0, 90] is then the angle above the scalp where
// it is vertical; it rises towards the crown, where the direction is the
// normal. 90 gives the normal everywhere (Bao & Qi 2017 Sec. IV-A, Table 1:
// "hair roots normal"). An elevation outside (0, 90] gives the normal.
// The root's direction is both the strand's first step and the interior
// field's Dirichlet value at the root (hybrid_field.h), so it bends the field
// near the scalp towards the way hair falls.
Eigen::Vector3d RootDirection(const Eigen::Vector3d& normal, const Eigen::Vector3d& down,
                              double elevation_deg);

// `count` roots uniform by area on the head's scalp, each with RootDirection
// at its normal; deterministic for a seed.
std::vector<DirectedRoot> SampleScalpRoots(const HeadModel& head, int count, uint64_t seed,
                                           double elevation_deg, const Eigen::Vector3d& down);

// Strands through the seen strands that the strands grown from the scalp
// leave uncovered (FieldGrowth::ThroughUncoveredSegments). Roots spread
// uniformly over the scalp follow the field and the seen strands near them,
// and neighbouring strands gather on the same seen strands: on tight curls the
// strands grown from 20,000 roots pass along about two thirds of what the
// segments themselves recover of the visible hair. A segment with at least
// min_uncovered_mm uncovered (segment_coverage.h) gets a strand of its own:
// traced from the segment's root end back through the field to the scalp
// (a scalp point within root_reach_mm), then the segment, then grown on from
// its tip end as every strand is. A segment the trace does not bring back to
// the scalp (on curls most such traces reach the face or temples below the
// hairline, where the views see skin) is grafted instead on the strand whose
// vertex lies nearest its root end, within graft_radius_mm and
// graft_max_angle_deg of its direction: the strand comes the way its
// neighbour came, then bends smoothly onto the seen strand. A segment that starts in front
// of skin the views see, or whose bridge would cross it, gets none. Not in Bao & Qi; `enabled =
// false` is the paper's growth.
struct SegmentCoverOptions {
  bool enabled = true;
  CoverageOptions coverage;
  double min_uncovered_mm = 5;
  double root_reach_mm = 1.5;
  double graft_radius_mm = 8;
  double graft_max_angle_deg = 60;
  Status Check() const;
};

struct StrandGrowthOptions {
  double step_mm = 1.0;  // delta of Eq. 2
  double max_length_mm = 400;
  double surface_threshold_mm = 0.1;  // T_s
  double volume_bound = 3.0;          // I_bound (I_d's units: mm at the grid's faces)
  double head_clearance_mm = 0.5;     // vertices are kept this far outside the head
  // Bao & Qi growth only: a strand that has come within off_hair_mm of a
  // segment stops once it has then run max_off_hair_mm (steps of step_mm)
  // further than off_hair_mm from every segment, and that stretch is dropped
  // (a strand left with its root alone counts as dropped_short). 0 (the
  // default, as the paper: I_d and the length only) turns the rule off; it
  // suits short hair and cuts long hair's strands where they pass under its
  // seen surface (docs/accuracy.md, "Strands").
  double max_off_hair_mm = 0;
  double off_hair_mm = 4;
  // Bao & Qi growth only: where the directed segment vertex nearest the
  // strand lies within follow_radius_mm and its tangent is within 60 deg of
  // the strand's direction, H gains follow_weight times that tangent: the strand
  // follows the seen strand at its own resolution, where S_s and V_i blur it
  // over 2 mm voxels. 0 turns it off (the paper's Eq. 1).
  double follow_radius_mm = 1.0;
  double follow_weight = 100;
  // Bao & Qi growth with views given: a strand ends at its first vertex
  // over skin (SkinViews::OverSkin, judged at the centre of the field voxel
  // it lies in: SkinGrid), which is dropped. false turns it off
  // (the paper: I_d and the length only).
  bool end_over_skin = true;
  SkinViewOptions skin;
  // Bao & Qi growth with views given: once a strand has stopped, the
  // vertices at its tip that lie over skin by the looser tip_skin test are
  // dropped (back to the last one that is not). A tip that hangs past the
  // hair's end is seen over skin by few of the views facing it (the others
  // see it against the hair around it), too few to end the growth (`skin`),
  // while a strand that crosses a gap between locks goes on over hair and
  // keeps its length. false turns it off.
  bool trim_tip_over_skin = true;
  SkinViewOptions tip_skin{2, 0.1};
  // The tip test counts a view's skin grown by this many pixels
  // (SkinViews::Grown): the segmentation's hair reaches a few pixels past the
  // hair's edge where its texture window straddles it, and a tip that ran on
  // along that edge, or past the end of sparse hair, is seen against hair
  // there. 0 tests the skin as labelled.
  int tip_skin_margin_px = 2;
  // Bao & Qi growth only: past the seen strands a curly strand carries its
  // curl on as a helix about the field's direction (helix_continuation.h,
  // or where the hair is seen to curl, the curl field's helix below); false
  // grows it along the field alone (the paper; docs/accuracy.md compares
  // them).
  bool helix_continuation = true;
  HelixContinuationOptions helix;
  // Bao & Qi growth only: where the hair is seen to curl (curl_field.h),
  // a strand past the seen strands winds on the estimated helix about the
  // field's direction (helix_guide.h) in place of the continuation above.
  // curl.enabled = false: the continuation everywhere.
  CurlFieldOptions curl;
  // Bao & Qi growth only: a strand that follows a seen strand to a tip end
  // that no other seen strand continues ends there (seen_tips.h; the tips
  // are found by the caller, SeenTips::Find). seen_tips.enabled = false: the
  // paper's growth, to the volume's edge.
  SeenTipOptions seen_tips;
  // Bao & Qi growth with the free space given (free_space.h): a strand
  // winding on a curl's helix whose next vertex would lie in front of the
  // seen hair, where the cameras see through, moves the helix's centre away
  // from that vertex, a step's length at a time (up to 4 per step), so the
  // helix winds within the hair: a helix placed by the seen surface's bend
  // swings half its turn out in front of the surface, and nothing there is
  // hair. The caller builds the free space with `free_space` (strand_
  // reconstruction.h, from the points and their views). false: the helix
  // keeps its centre (docs/accuracy.md compares them).
  bool helix_out_of_free_space = true;
  FreeSpaceOptions free_space;
  SegmentCoverOptions cover;  // Bao & Qi growth only
  int threads = 2;

  Status Check() const;
};

struct StrandGrowthSummary {
  int64_t strands = 0, vertices = 0;
  int64_t stopped_volume = 0, stopped_length = 0, stopped_off_hair = 0, stopped_over_skin = 0,
          stopped_seen_tip = 0, dropped_short = 0;
  int64_t tips_trimmed_over_skin = 0;  // kept strands whose tip trim_tip_over_skin shortened
  // Moves of a helix's centre out of the free space (helix_out_of_free_space).
  int64_t helix_moves_from_free_space = 0;
  // The seen tips strands could end at (SeenTips::size; set by the caller that
  // found them) of the seen strands' tip ends looked at.
  int64_t seen_tips = 0, seen_tip_ends_examined = 0;
  // SegmentCoverOptions: segments uncovered after the growth from the roots;
  // strands added through them (counted in `strands`); segments whose trace
  // back did not reach the scalp and that no strand passed near; segments
  // whose strand was trimmed back from skin to its root alone (not added); of
  // the strands added, those grafted on another strand.
  int64_t cover_candidates = 0, cover_strands = 0, cover_no_root = 0, cover_trimmed_away = 0,
          cover_grafted = 0;
  double mean_length_mm = 0;
};

// Bao & Qi's growth in a hybrid field. `head` (may be null: no head, no
// strands through segments), `skin` (may be null: no skin test), `curls`
// (may be null: no curl field), `seen_tips` (may be null: strands do not
// end at seen tips) and `free_space` (may be null: helices wind where they
// will) in the field's frame; all six and `options` must outlive the object.
class FieldGrowth {
 public:
  FieldGrowth(const HybridOrientationField& field, const HeadModel* head,
              const StrandGrowthOptions& options, const SkinViews* skin,
              const CurlField* curls = nullptr, const SeenTips* seen_tips = nullptr,
              const FreeSpace* free_space = nullptr);
  ~FieldGrowth();

  // Eq. 2 from each root. Strands shorter than 2 vertices are dropped.
  StrandSet FromRoots(const std::vector<DirectedRoot>& roots, StrandGrowthSummary* summary) const;
  // Appends to *strands a strand through every segment (root to tip, as
  // strand_direction.h directs them) that *strands leave uncovered
  // (SegmentCoverOptions), most uncovered first, and updates the summary's
  // counts and mean length for the whole set. Nothing without a head or with
  // the option off.
  void ThroughUncoveredSegments(const std::vector<StrandSegment>& segments, StrandSet* strands,
                                StrandGrowthSummary* summary) const;

 private:
  struct Skin;
  class Step;
  // The strand through one segment (see SegmentCoverOptions); nullopt when
  // it has none. `strands` with their `offsets` (StrandSet::Offsets) are the
  // strands `coverage` holds.
  std::optional<std::vector<Eigen::Vector3f>> ThroughSegment(const StrandSegment& segment,
                                                             const StrandSet& strands,
                                                             const std::vector<size_t>& offsets,
                                                             const StrandCoverage& coverage,
                                                             bool* grafted) const;
  // The strand's path from the scalp to the segment's root end (root first),
  // traced back through the field or else grafted on a strand; *grafted says
  // which. The traced path ends at the segment's first vertex; the grafted
  // one is the strand up to the vertex it leaves, then a cubic Hermite bridge
  // (step_mm apart) up to, not including, the segment's first vertex.
  std::optional<std::vector<Eigen::Vector3f>> FromScalpTo(const StrandSegment& segment,
                                                          const StrandSet& strands,
                                                          const std::vector<size_t>& offsets,
                                                          const StrandCoverage& coverage,
                                                          bool* grafted) const;
  // Drops the tip's vertices over skin (trim_tip_over_skin); returns how many.
  size_t TrimTip(std::vector<Eigen::Vector3f>* strand) const;

  const HybridOrientationField& field_;
  const HeadModel* head_;
  const StrandGrowthOptions& o_;
  std::unique_ptr<Skin> skin_;
  const CurlField* curls_;
  const SeenTips* seen_tips_;
  // FreeSpace::Free once per half voxel of the field's grid; null without a free space.
  std::unique_ptr<const VoxelCache> free_;
  mutable std::atomic<int64_t> helix_moves_{0};
};

// FieldGrowth(field, head, options, skin).FromRoots(roots, summary).
StrandSet GrowStrandsInField(const HybridOrientationField& field,
                             const std::vector<DirectedRoot>& roots, const HeadModel* head,
                             const StrandGrowthOptions& options,
                             StrandGrowthSummary* summary = nullptr,
                             const SkinViews* skin = nullptr);

// The naive baseline from each root along the points' orientation.
StrandSet GrowStrandsAlongPoints(const PointOrientationField& points,
                                 const std::vector<DirectedRoot>& roots, const HeadModel* head,
                                 const StrandGrowthOptions& options,
                                 StrandGrowthSummary* summary = nullptr);

}  // namespace hairrig
