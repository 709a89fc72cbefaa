#include "reconstruction/strand_growth.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <random>

#include "core/parallel.h"

namespace hairrig {

namespace {

enum class End { kVolume, kLength, kOffHair, kOverSkin };

// What a step decided besides the next direction.
struct StepStop {
  End end = End::kLength;  // why the strand stops (a step that returns false)
  int drop_last = 0;       // vertices at the strand's end to drop when it stops
};

// Grows every root's strand with `step(previous vertex, previous direction,
// &next direction, &stop) -> false to stop`, in parallel, in root order; then
// `trim_tip(strand) -> vertices dropped` shortens each grown strand at its tip.
template <typename MakeStep, typename TrimTip>
StrandSet GrowAll(const std::vector<DirectedRoot>& roots, const HeadModel* head,
                  const StrandGrowthOptions& o, MakeStep make_step, TrimTip trim_tip,
                  StrandGrowthSummary* summary) {
  std::vector<std::vector<Eigen::Vector3f>> strands(roots.size());
  std::vector<End> ends(roots.size(), End::kLength);
  std::vector<uint8_t> trimmed(roots.size(), 0);
  const int max_steps = static_cast<int>(o.max_length_mm / o.step_mm);
  ParallelFor(roots.size(), o.threads, [&] {
    return [&](size_t r) {
      auto step = make_step();  // per strand: a step may keep state along its strand
      std::vector<Eigen::Vector3f>& strand = strands[r];
      Eigen::Vector3f p = roots[r].position_mm, direction = roots[r].direction;
      strand.push_back(p);
      for (int i = 0; i < max_steps; ++i) {
        Eigen::Vector3f next = direction;
        StepStop stop;
        if (!step(p, direction, &next, &stop)) {
          ends[r] = stop.end;
          strand.resize(strand.size() - std::min<size_t>(strand.size() - 1, stop.drop_last));
          break;
        }
        p += next * static_cast<float>(o.step_mm);
        if (head != nullptr)
          p = head->KeepOutside(p.cast<double>(), o.head_clearance_mm).cast<float>();
        strand.push_back(p);
        direction = next;
      }
      trimmed[r] = trim_tip(strand) > 0;
    };
  });
  StrandSet set;
  StrandGrowthSummary s;
  double length = 0;
  for (size_t r = 0; r < strands.size(); ++r) {
    if (strands[r].size() < 2) {
      ++s.dropped_short;
      continue;
    }
    ++(ends[r] == End::kVolume     ? s.stopped_volume
       : ends[r] == End::kOffHair  ? s.stopped_off_hair
       : ends[r] == End::kOverSkin ? s.stopped_over_skin
                                   : s.stopped_length);
    s.tips_trimmed_over_skin += trimmed[r];
    set.AddStrand(strands[r]);
    s.vertices += static_cast<int64_t>(strands[r].size());
    length += static_cast<double>(strands[r].size() - 1) * o.step_mm;
  }
  s.strands = static_cast<int64_t>(set.num_strands());
  s.mean_length_mm = s.strands > 0 ? length / static_cast<double>(s.strands) : 0;
  if (summary != nullptr) *summary = s;
  return set;
}

// StrandGrowthOptions::max_off_hair_mm (when positive) along one strand, a
// vertex (one step) at a time.
class OffHairRun {
 public:
  explicit OffHairRun(const StrandGrowthOptions& o)
      : step_mm_(o.step_mm), off_hair_mm_(o.off_hair_mm), max_off_hair_mm_(o.max_off_hair_mm) {}

  // True when the strand ends at its last vertex, `segment_distance_mm` from
  // the nearest segment; then *drop_last is the count of its vertices grown
  // off the hair, that one included.
  bool Ended(double segment_distance_mm, int* drop_last) {
    if (segment_distance_mm < off_hair_mm_) {
      reached_ = true;
      off_vertices_ = 0;
      return false;
    }
    if (!reached_) return false;
    ++off_vertices_;
    if (off_vertices_ * step_mm_ <= max_off_hair_mm_) return false;
    *drop_last = off_vertices_;
    return true;
  }

 private:
  double step_mm_, off_hair_mm_, max_off_hair_mm_;
  bool reached_ = false;
  int off_vertices_ = 0;
};

}  // namespace

Eigen::Vector3d RootDirection(const Eigen::Vector3d& normal, const Eigen::Vector3d& down,
                              double elevation_deg) {
  if (!(elevation_deg > 0 && elevation_deg <= 90)) return normal;
  const double elevation = elevation_deg * M_PI / 180.0;
  const Eigen::Vector3d down_along_scalp = down - down.dot(normal) * normal;
  const Eigen::Vector3d d = std::sin(elevation) * normal + std::cos(elevation) * down_along_scalp;
  return d.norm() > 1e-9 ? d.normalized() : normal;
}

std::vector<DirectedRoot> SampleScalpRoots(const HeadModel& head, int count, uint64_t seed,
                                           double elevation_deg, const Eigen::Vector3d& down) {
  std::mt19937_64 rng(seed);
  std::vector<DirectedRoot> roots(static_cast<size_t>(std::max(count, 0)));
  for (DirectedRoot& root : roots) {
    Eigen::Vector3d normal;
    root.position_mm = head.SampleScalp(rng, &normal).cast<float>();
    root.direction = RootDirection(normal, down, elevation_deg).cast<float>();
  }
  return roots;
}

Status StrandGrowthOptions::Check() const {
  if (!(step_mm > 0)) return InvalidArgument("strand step_mm must be positive");
  if (!(max_length_mm > step_mm))
    return InvalidArgument("strand max_length_mm must exceed step_mm");
  if (!(surface_threshold_mm >= 0))
    return InvalidArgument("strand surface_threshold_mm must be non-negative");
  if (!(volume_bound > 0)) return InvalidArgument("strand volume_bound must be positive");
  if (!(head_clearance_mm >= 0))
    return InvalidArgument("strand head_clearance_mm must be non-negative");
  if (!(max_off_hair_mm >= 0))
    return InvalidArgument("strand max_off_hair_mm must be non-negative (0 turns it off)");
  if (!(off_hair_mm > 0)) return InvalidArgument("strand off_hair_mm must be positive");
  if (!(follow_radius_mm >= 0 && follow_radius_mm <= 10))
    return InvalidArgument("strand follow_radius_mm must lie in [0, 10] (0 turns it off)");
  if (!(follow_weight >= 0)) return InvalidArgument("strand follow_weight must be non-negative");
  if (tip_skin_margin_px < 0 || tip_skin_margin_px > 20)
    return InvalidArgument(
        "strand tip_skin_margin_px must lie in 0..20 (0 tests the skin as labelled)");
  HR_RETURN_IF_ERROR(skin.Check());
  return tip_skin.Check();
}

StrandSet GrowStrandsInField(const HybridOrientationField& field,
                             const std::vector<DirectedRoot>& roots, const HeadModel* head,
                             const StrandGrowthOptions& o, StrandGrowthSummary* summary,
                             const SkinViews* skin) {
  // The skin test once per voxel of the field's grid: a strand's every step
  // asks it, and projecting into every view each time doubles the growth's time.
  std::unique_ptr<const SkinGrid> skin_grid, tip_skin_grid;
  if (o.end_over_skin && skin != nullptr)
    skin_grid = std::make_unique<const SkinGrid>(*skin, o.skin, field.origin(), field.size(),
                                                 field.voxel_mm());
  std::optional<SkinViews> tip_views;
  if (o.trim_tip_over_skin && skin != nullptr) {
    tip_views = skin->Grown(o.tip_skin_margin_px);
    tip_skin_grid = std::make_unique<const SkinGrid>(*tip_views, o.tip_skin, field.origin(),
                                                     field.size(), field.voxel_mm());
  }
  const auto trim_tip = [&](std::vector<Eigen::Vector3f>& strand) -> size_t {
    if (!tip_skin_grid) return 0;
    size_t keep = strand.size();
    while (keep > 1 && tip_skin_grid->OverSkin(strand[keep - 1])) --keep;
    const size_t dropped = strand.size() - keep;
    strand.resize(keep);
    return dropped;
  };
  const auto make_step = [&] {
    return [&, off_hair = OffHairRun(o), helix = HelixContinuation(o.helix, o.step_mm),
            axis = Eigen::Vector3f(),
            continuing = false](const Eigen::Vector3f& p, const Eigen::Vector3f& previous,
                                Eigen::Vector3f* next, StepStop* stop) mutable {
      if (!field.Contains(p) || field.Distance(p) > o.volume_bound) {
        stop->end = End::kVolume;
        return false;
      }
      if (o.max_off_hair_mm > 0 && off_hair.Ended(field.SegmentDistance(p), &stop->drop_last)) {
        stop->end = End::kOffHair;
        return false;
      }
      if (skin_grid && skin_grid->OverSkin(p)) {
        stop->end = End::kOverSkin;
        stop->drop_last = 1;
        return false;
      }
      // Eq. 1 with the paper's dynamic weights (Sec. IV-B); on a helix carried
      // on, about the axis the field gave the step before.
      const Eigen::Vector3f& way = continuing ? axis : previous;
      const double d_s = field.RibbonDistance(p);
      double a_s = 0, a_i = 100 * d_s;
      if (d_s < o.surface_threshold_mm) a_s = 100 - d_s, a_i = 0.1;
      const double a_d = 0.1 * a_i, a_g = 10;
      Eigen::Vector3f h = static_cast<float>(a_i) * field.Interior(p, way) -
                          static_cast<float>(a_d) * field.DistanceGradient(p) +
                          static_cast<float>(a_g) * way;
      if (a_s > 0) h += static_cast<float>(a_s) * field.Surface(p, way);
      // The seen strand at p itself, where one runs within follow_radius_mm
      // in about the strand's direction (StrandGrowthOptions).
      Eigen::Vector3f seen;
      const bool following = o.follow_radius_mm > 0 &&
                             field.NearestSegmentTangent(p, o.follow_radius_mm, &seen) &&
                             seen.dot(previous) > 0.5f;
      if (following) h += static_cast<float>(o.follow_weight) * seen;
      if (h.norm() < 1e-6f) return true;  // keeps the previous direction
      *next = h.normalized();
      if (!o.helix_continuation) return true;
      continuing = false;
      if (following) {
        helix.Follow(*next);
      } else {
        axis = *next;
        continuing = helix.Continue(previous, axis, next);
      }
      return true;
    };
  };
  return GrowAll(roots, head, o, make_step, trim_tip, summary);
}

StrandSet GrowStrandsAlongPoints(const PointOrientationField& points,
                                 const std::vector<DirectedRoot>& roots, const HeadModel* head,
                                 const StrandGrowthOptions& o, StrandGrowthSummary* summary) {
  const auto make_step = [&] {
    return [&, reached = false](const Eigen::Vector3f& p, const Eigen::Vector3f& previous,
                                Eigen::Vector3f* next, StepStop* stop) mutable {
      Eigen::Vector3f orientation;
      const bool near = points.At(p, previous, 0.0, 1, &orientation);
      stop->end = End::kVolume;
      if (!near) return !reached;  // straight on until the points are reached; stop on leaving them
      reached = true;
      *next = orientation;
      return true;
    };
  };
  const auto keep_tip = [](const std::vector<Eigen::Vector3f>&) { return size_t{0}; };
  return GrowAll(roots, head, o, make_step, keep_tip, summary);
}

}  // namespace hairrig
