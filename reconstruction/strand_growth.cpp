#include "reconstruction/strand_growth.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <random>

#include "core/parallel.h"
#include "reconstruction/segment_coverage.h"

namespace hairrig {

namespace {

enum class End { kVolume, kLength, kOffHair, kOverSkin, kSeenTip, kRoot };

// What a step decided besides the next direction.
struct StepStop {
  End end = End::kLength;  // why the strand stops (a step that returns false)
  int drop_last = 0;       // vertices at the strand's end to drop when it stops
};

// Grows one strand from `p` (already its last vertex) in `direction` with
// `step(previous vertex, previous direction, &next direction, &stop) -> false
// to stop`, for at most `max_steps` steps; returns why it stopped.
template <typename Step>
End GrowFrom(Eigen::Vector3f p, Eigen::Vector3f direction, int max_steps, Step& step,
             const HeadModel* head, const StrandGrowthOptions& o,
             std::vector<Eigen::Vector3f>* strand) {
  for (int i = 0; i < max_steps; ++i) {
    Eigen::Vector3f next = direction;
    StepStop stop;
    if (!step(p, direction, &next, &stop)) {
      strand->resize(strand->size() - std::min<size_t>(strand->size() - 1, stop.drop_last));
      return stop.end;
    }
    p += next * static_cast<float>(o.step_mm);
    if (head != nullptr) p = head->KeepOutside(p.cast<double>(), o.head_clearance_mm).cast<float>();
    strand->push_back(p);
    direction = next;
  }
  return End::kLength;
}

int MaxSteps(const StrandGrowthOptions& o, double length_mm) {
  return static_cast<int>(length_mm / o.step_mm);
}

// Grows every root's strand with a fresh `make_step()` (a step may keep state
// along its strand; see GrowFrom), in parallel, in root order; then
// `trim_tip(strand) -> vertices dropped` shortens each grown strand at its tip.
template <typename MakeStep, typename TrimTip>
StrandSet GrowAll(const std::vector<DirectedRoot>& roots, const HeadModel* head,
                  const StrandGrowthOptions& o, MakeStep make_step, TrimTip trim_tip,
                  StrandGrowthSummary* summary) {
  std::vector<std::vector<Eigen::Vector3f>> strands(roots.size());
  std::vector<End> ends(roots.size(), End::kLength);
  std::vector<uint8_t> trimmed(roots.size(), 0);
  ParallelFor(roots.size(), o.threads, [&] {
    return [&](size_t r) {
      auto step = make_step();
      std::vector<Eigen::Vector3f>& strand = strands[r];
      strand.push_back(roots[r].position_mm);
      ends[r] = GrowFrom(roots[r].position_mm, roots[r].direction, MaxSteps(o, o.max_length_mm),
                         step, head, o, &strand);
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
       : ends[r] == End::kSeenTip  ? s.stopped_seen_tip
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
  HR_RETURN_IF_ERROR(cover.Check());
  HR_RETURN_IF_ERROR(curl.Check());
  HR_RETURN_IF_ERROR(seen_tips.Check());
  HR_RETURN_IF_ERROR(free_space.Check());
  return tip_skin.Check();
}

Status SegmentCoverOptions::Check() const {
  if (!(coverage.radius_mm > 0 && coverage.radius_mm <= 10))
    return InvalidArgument("strand cover radius_mm must lie in (0, 10]");
  if (!(coverage.max_angle_deg > 0 && coverage.max_angle_deg <= 90))
    return InvalidArgument("strand cover max_angle_deg must lie in (0, 90]");
  if (!(min_uncovered_mm > 0))
    return InvalidArgument("strand cover min_uncovered_mm must be positive");
  if (!(root_reach_mm > 0)) return InvalidArgument("strand cover root_reach_mm must be positive");
  if (!(graft_radius_mm >= 0 && graft_radius_mm <= 20))
    return InvalidArgument("strand cover graft_radius_mm must lie in [0, 20] (0: no graft)");
  if (!(graft_max_angle_deg > 0 && graft_max_angle_deg <= 90))
    return InvalidArgument("strand cover graft_max_angle_deg must lie in (0, 90]");
  return Status::Ok();
}

// The skin tests of a growth in the field, once per voxel of the field's
// grid: a strand's every step asks them, and projecting into every view each
// time doubles the growth's time.
struct FieldGrowth::Skin {
  std::unique_ptr<const SkinGrid> ends;  // end_over_skin
  std::optional<SkinViews> tip_views;    // the views' skin grown by tip_skin_margin_px
  std::unique_ptr<const SkinGrid> tips;  // trim_tip_over_skin
};

// Eq. 2's step in the hybrid field for one strand (it keeps the strand's
// off-hair run and helix), walking root to tip, or tip to root with
// `towards_root` (every directed term of H reversed; the strand then stops at
// the scalp: End::kRoot).
class FieldGrowth::Step {
 public:
  // `grown_mm`: the strand's length before this Step's first step.
  Step(const FieldGrowth& growth, bool towards_root, double grown_mm = 0)
      : g_(growth),
        sign_(towards_root ? -1.f : 1.f),
        off_hair_(growth.o_),
        helix_(growth.o_.helix, growth.o_.step_mm),
        guide_(growth.o_.step_mm),
        grown_mm_(grown_mm) {}

  bool operator()(const Eigen::Vector3f& p, const Eigen::Vector3f& previous, Eigen::Vector3f* next,
                  StepStop* stop) {
    const StrandGrowthOptions& o = g_.o_;
    const HybridOrientationField& field = g_.field_;
    if (sign_ < 0 && AtScalp(p)) {
      stop->end = End::kRoot;
      return false;
    }
    // A strand winding on a curl's helix swings its radius about the curl's
    // centre line: it leaves the hair when both have.
    double out_of_hair = field.Distance(p);
    if (guide_.active())
      out_of_hair = std::min(out_of_hair, field.Distance(guide_.centre().cast<float>()));
    if (!field.Contains(p) || out_of_hair > o.volume_bound) {
      stop->end = End::kVolume;
      return false;
    }
    if (o.max_off_hair_mm > 0 && off_hair_.Ended(field.SegmentDistance(p), &stop->drop_last)) {
      stop->end = End::kOffHair;
      return false;
    }
    if (g_.skin_->ends && g_.skin_->ends->OverSkin(p)) {
      stop->end = End::kOverSkin;
      stop->drop_last = 1;
      return false;
    }
    // Eq. 1 with the paper's dynamic weights (Sec. IV-B); on a helix carried
    // on, about the axis the field gave the step before.
    const Eigen::Vector3f& way = continuing_ ? axis_ : previous;
    const Eigen::Vector3f field_way = sign_ * way;  // the field's own (root to tip) sense
    const double d_s = field.RibbonDistance(p);
    double a_s = 0, a_i = 100 * d_s;
    if (d_s < o.surface_threshold_mm) a_s = 100 - d_s, a_i = 0.1;
    const double a_d = 0.1 * a_i, a_g = 10;
    Eigen::Vector3f h = sign_ * static_cast<float>(a_i) * field.Interior(p, field_way) -
                        static_cast<float>(a_d) * field.DistanceGradient(p) +
                        static_cast<float>(a_g) * way;
    if (a_s > 0) h += sign_ * static_cast<float>(a_s) * field.Surface(p, field_way);
    // The seen strand at p itself, where one runs within follow_radius_mm
    // in about the strand's direction (StrandGrowthOptions).
    Eigen::Vector3f seen;
    const bool following = o.follow_radius_mm > 0 &&
                           field.NearestSegmentTangent(p, o.follow_radius_mm, &seen) &&
                           sign_ * seen.dot(previous) > 0.5f;
    grown_mm_ += o.step_mm;
    if (following && sign_ > 0 && grown_mm_ > o.seen_tips.min_strand_mm && AtSeenTip(p, previous)) {
      stop->end = End::kSeenTip;
      return false;
    }
    if (following) h += sign_ * static_cast<float>(o.follow_weight) * seen;
    if (h.norm() < 1e-6f) return true;  // keeps the previous direction
    *next = h.normalized();
    if (!o.helix_continuation) return true;
    continuing_ = false;
    if (following) {
      helix_.Follow(*next);
      ++followed_steps_;
      guide_.Stop();
      return true;
    }
    const int followed_steps = followed_steps_;
    followed_steps_ = 0;
    if (const Curl* curl = d_s >= o.curl.min_depth_mm && g_.curls_ ? g_.curls_->At(p) : nullptr) {
      axis_ = *next;
      if (!guide_.active()) on_bend_ = StartHelix(p, previous, followed_steps, *curl);
      if (on_bend_) {
        const Eigen::Vector3f held = guide_.axis();
        const float pull = static_cast<float>(o.step_mm / o.curl.bend_axis_relax_mm);
        axis_ =
            (held + pull * (axis_.dot(held) >= 0 ? axis_ : Eigen::Vector3f(-axis_))).normalized();
      }
      *next = guide_.Next(p, axis_);
      KeepOutOfFreeSpace(p, next);
      continuing_ = true;
    } else {
      guide_.Stop();
      axis_ = *next;
      continuing_ = helix_.Continue(previous, axis_, next);
    }
    return true;
  }

 private:
  // A seen tip (seen_tips.h) at p, in the strand's direction, where the hair
  // is not seen to curl: there a seen strand ends where it turns out of the
  // views' sight more often than where it ends (docs/accuracy.md, "Where
  // strands end").
  bool AtSeenTip(const Eigen::Vector3f& p, const Eigen::Vector3f& direction) const {
    if (g_.seen_tips_ == nullptr || !g_.seen_tips_->Reached(p, direction)) return false;
    return g_.curls_ == nullptr || g_.curls_->At(p) == nullptr;
  }
  // Starts the curl's helix at p, where the strand (last direction
  // `previous`) has just followed `followed_steps` steps of a seen strand:
  // on that stretch's bend where it bends enough (CurlFieldOptions::
  // start_on_bend), else about the field's direction axis_.
  // True when it started on the bend.
  bool StartHelix(const Eigen::Vector3f& p, const Eigen::Vector3f& previous, int followed_steps,
                  const Curl& curl) {
    const CurlFieldOptions& c = g_.o_.curl;
    const auto span =
        static_cast<size_t>(std::max(1.0, std::round(c.bend_span_mm / g_.o_.step_mm)));
    Eigen::Vector3f bend_tangent, bend_normal;
    if (c.start_on_bend && followed_steps > static_cast<int>(span) &&
        helix_.Bend(span, c.min_bend_deg * M_PI / 180, &bend_tangent, &bend_normal)) {
      guide_.StartOnBend(p, previous, bend_tangent, bend_normal, curl);
      return true;
    }
    guide_.Start(p, previous, axis_, curl);
    return false;
  }
  // Moves the helix's centre a step at a time away from its next vertex
  // while that vertex lies in the free space (helix_out_of_free_space), and
  // turns *next towards the moved helix's point.
  void KeepOutOfFreeSpace(const Eigen::Vector3f& p, Eigen::Vector3f* next) {
    constexpr int kMaxMoves = 4;
    if (!g_.free_) return;
    const auto step = static_cast<float>(g_.o_.step_mm);
    for (int move = 0; move < kMaxMoves && (*g_.free_)(p + step * *next); ++move) {
      if (!guide_.MoveCentreAwayFrom(p + step * *next, g_.o_.step_mm)) return;
      *next = guide_.Towards(p);
      g_.helix_moves_.fetch_add(1, std::memory_order_relaxed);
    }
  }
  bool AtScalp(const Eigen::Vector3f& p) const {
    if (g_.head_ == nullptr) return false;
    const Eigen::Vector3d q = p.cast<double>();
    Eigen::Vector3d outward;
    return g_.head_->SignedDistance(q, &outward) <= g_.o_.cover.root_reach_mm &&
           g_.head_->OnScalp(q);
  }

  const FieldGrowth& g_;
  float sign_;
  OffHairRun off_hair_;
  HelixContinuation helix_;
  HelixGuide guide_;
  Eigen::Vector3f axis_ = Eigen::Vector3f::Zero();
  bool continuing_ = false;
  int followed_steps_ = 0;  // steps in a row that followed a seen strand, up to the last
  bool on_bend_ = false;    // the helix being wound started on a followed bend
  double grown_mm_;         // the strand's length so far (mm)
};

FieldGrowth::FieldGrowth(const HybridOrientationField& field, const HeadModel* head,
                         const StrandGrowthOptions& options, const SkinViews* skin,
                         const CurlField* curls, const SeenTips* seen_tips,
                         const FreeSpace* free_space)
    : field_(field),
      head_(head),
      o_(options),
      skin_(std::make_unique<Skin>()),
      curls_(curls),
      seen_tips_(seen_tips) {
  // Only strands winding on a curl ask (KeepOutOfFreeSpace): no cache where nothing curls.
  if (o_.helix_out_of_free_space && free_space != nullptr && curls != nullptr &&
      curls->estimate().curl.curly()) {
    free_ = std::make_unique<const VoxelCache>(
        [free_space](const Eigen::Vector3f& p) { return free_space->Free(p.cast<double>()); },
        field.origin(), field.size() * 2, field.voxel_mm() / 2);
  }
  if (o_.end_over_skin && skin != nullptr)
    skin_->ends = std::make_unique<const SkinGrid>(*skin, o_.skin, field.origin(), field.size(),
                                                   field.voxel_mm());
  if (o_.trim_tip_over_skin && skin != nullptr) {
    skin_->tip_views = skin->Grown(o_.tip_skin_margin_px);
    skin_->tips = std::make_unique<const SkinGrid>(*skin_->tip_views, o_.tip_skin, field.origin(),
                                                   field.size(), field.voxel_mm());
  }
}

FieldGrowth::~FieldGrowth() = default;

size_t FieldGrowth::TrimTip(std::vector<Eigen::Vector3f>* strand) const {
  if (!skin_->tips) return 0;
  size_t keep = strand->size();
  while (keep > 1 && skin_->tips->OverSkin((*strand)[keep - 1])) --keep;
  const size_t dropped = strand->size() - keep;
  strand->resize(keep);
  return dropped;
}

StrandSet FieldGrowth::FromRoots(const std::vector<DirectedRoot>& roots,
                                 StrandGrowthSummary* summary) const {
  const auto make_step = [&] { return Step(*this, false); };
  const auto trim_tip = [&](std::vector<Eigen::Vector3f>& strand) { return TrimTip(&strand); };
  StrandSet strands = GrowAll(roots, head_, o_, make_step, trim_tip, summary);
  if (summary != nullptr) summary->helix_moves_from_free_space = helix_moves_.load();
  return strands;
}

std::optional<std::vector<Eigen::Vector3f>> FieldGrowth::FromScalpTo(
    const StrandSegment& segment, const StrandSet& strands, const std::vector<size_t>& offsets,
    const StrandCoverage& coverage, bool* grafted) const {
  const std::vector<Eigen::Vector3f>& seen = segment.points_mm;
  const Eigen::Vector3f tangent = PolylineTangent(seen.data(), seen.size(), 0);
  if (skin_->ends && skin_->ends->OverSkin(seen.front())) return std::nullopt;
  std::vector<Eigen::Vector3f> back = {seen.front()};
  Step to_root(*this, true);
  if (GrowFrom(seen.front(), -tangent, MaxSteps(o_, o_.max_length_mm - segment.Length()), to_root,
               head_, o_, &back) == End::kRoot) {
    *grafted = false;
    return std::vector<Eigen::Vector3f>(back.rbegin(), back.rend());
  }
  const SegmentCoverOptions& c = o_.cover;
  if (c.graft_radius_mm <= 0) return std::nullopt;
  const StrandCoverage::Vertex graft = coverage.Nearest(
      seen.front(), tangent, c.graft_radius_mm, std::cos(c.graft_max_angle_deg * M_PI / 180.0));
  if (graft.strand < 0) return std::nullopt;
  *grafted = true;
  // The strand is left as far before its nearest vertex as that lies from the
  // segment, so the bridge turns by about 45 deg at most over a gap square to the hair.
  const auto first = strands.points_mm.begin() + static_cast<ptrdiff_t>(offsets[graft.strand]);
  const float gap_beside = (first[graft.vertex] - seen.front()).norm();
  const int leave = std::max(
      0, graft.vertex - static_cast<int>(std::ceil(gap_beside / static_cast<float>(o_.step_mm))));
  std::vector<Eigen::Vector3f> path(first, first + leave + 1);
  // A cubic Hermite bridge from there, in its strand's direction, to the
  // segment's first vertex, in the segment's: no kink at either end.
  const Eigen::Vector3f from = path.back(), to = seen.front();
  const float gap = (to - from).norm();
  const Eigen::Vector3f from_tangent =
      gap * PolylineTangent(&*first, offsets[graft.strand + 1] - offsets[graft.strand],
                            static_cast<size_t>(leave));
  const Eigen::Vector3f to_tangent = gap * tangent;
  if (gap < 1e-3f) path.pop_back();  // the segment starts there
  const int pieces = static_cast<int>(std::ceil(gap / o_.step_mm));
  for (int i = 1; i < pieces; ++i) {
    const float t = static_cast<float>(i) / static_cast<float>(pieces), t2 = t * t, t3 = t2 * t;
    path.push_back((2 * t3 - 3 * t2 + 1) * from + (t3 - 2 * t2 + t) * from_tangent +
                   (-2 * t3 + 3 * t2) * to + (t3 - t2) * to_tangent);
    // The bridge crosses no skin the views see, as no grown strand does.
    if (skin_->ends && skin_->ends->OverSkin(path.back())) return std::nullopt;
  }
  return path;
}

std::optional<std::vector<Eigen::Vector3f>> FieldGrowth::ThroughSegment(
    const StrandSegment& segment, const StrandSet& strands, const std::vector<size_t>& offsets,
    const StrandCoverage& coverage, bool* grafted) const {
  auto strand = FromScalpTo(segment, strands, offsets, coverage, grafted);
  if (!strand) return std::nullopt;
  const std::vector<Eigen::Vector3f>& seen = segment.points_mm;
  strand->insert(strand->end(), seen.begin() + (*grafted ? 0 : 1), seen.end());
  // On from the segment's tip end as any strand grows.
  const double length_mm = StrandSegment{*strand}.Length();
  Step to_tip(*this, false, length_mm);
  GrowFrom(seen.back(), PolylineTangent(seen.data(), seen.size(), seen.size() - 1),
           MaxSteps(o_, o_.max_length_mm - length_mm), to_tip, head_, o_, &*strand);
  TrimTip(&*strand);
  return strand;
}

void FieldGrowth::ThroughUncoveredSegments(const std::vector<StrandSegment>& segments,
                                           StrandSet* strands, StrandGrowthSummary* summary) const {
  const SegmentCoverOptions& c = o_.cover;
  if (!c.enabled || head_ == nullptr) return;
  StrandCoverage coverage(c.coverage);
  coverage.Add(*strands);
  // The candidates, most uncovered first; a strand added for one may cover the next.
  std::vector<double> uncovered(segments.size());
  ParallelFor(segments.size(), o_.threads, [&] {
    return [&](size_t k) { uncovered[k] = coverage.UncoveredLengthMm(segments[k]); };
  });
  std::vector<size_t> order;
  for (size_t k = 0; k < segments.size(); ++k)
    if (uncovered[k] >= c.min_uncovered_mm) order.push_back(k);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return uncovered[a] > uncovered[b]; });
  StrandGrowthSummary local;
  StrandGrowthSummary& s = summary != nullptr ? *summary : local;
  s.cover_candidates = static_cast<int64_t>(order.size());
  std::vector<size_t> offsets = strands->Offsets();
  const auto still_uncovered = [&](size_t k) {
    return coverage.UncoveredLengthMm(segments[k]) >= c.min_uncovered_mm;
  };
  // Batches of candidates grow in parallel against the cover as it stood
  // before the batch, then are added in order, each only if the strands added
  // before it still leave it uncovered: the same strands on any thread count.
  constexpr size_t kBatch = 64;
  for (size_t begin = 0; begin < order.size(); begin += kBatch) {
    const size_t count = std::min(kBatch, order.size() - begin);
    std::vector<std::optional<std::vector<Eigen::Vector3f>>> grown(count);
    std::vector<uint8_t> tried(count, 0), grafted(count, 0);
    ParallelFor(count, o_.threads, [&] {
      return [&](size_t i) {
        const size_t k = order[begin + i];
        if (!still_uncovered(k)) return;
        tried[i] = 1;
        bool g = false;
        grown[i] = ThroughSegment(segments[k], *strands, offsets, coverage, &g);
        grafted[i] = g;
      };
    });
    bool added = false;
    for (size_t i = 0; i < count; ++i) {
      const size_t k = order[begin + i];
      if (!tried[i] || (added && !still_uncovered(k))) continue;
      if (!grown[i] && added) {  // a strand added since may be near enough to graft on
        bool g = false;
        grown[i] = ThroughSegment(segments[k], *strands, offsets, coverage, &g);
        grafted[i] = g;
      }
      if (!grown[i]) {
        ++s.cover_no_root;
        continue;
      }
      if (grown[i]->size() < 2) {  // TrimTip left the root alone: the whole strand lies over skin
        ++s.cover_trimmed_away;
        continue;
      }
      added = true;
      coverage.Add(*grown[i]);
      strands->AddStrand(*grown[i]);
      offsets.push_back(strands->num_points());
      ++s.cover_strands;
      s.cover_grafted += grafted[i];
    }
  }
  const std::vector<double> lengths = strands->StrandLengths();
  s.helix_moves_from_free_space = helix_moves_.load();
  s.strands = static_cast<int64_t>(strands->num_strands());
  s.vertices = static_cast<int64_t>(strands->num_points());
  s.mean_length_mm = lengths.empty() ? 0
                                     : std::accumulate(lengths.begin(), lengths.end(), 0.0) /
                                           static_cast<double>(lengths.size());
}

StrandSet GrowStrandsInField(const HybridOrientationField& field,
                             const std::vector<DirectedRoot>& roots, const HeadModel* head,
                             const StrandGrowthOptions& o, StrandGrowthSummary* summary,
                             const SkinViews* skin) {
  return FieldGrowth(field, head, o, skin).FromRoots(roots, summary);
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
