// Connection analysis (Sec. 6.1): the links between ribbons from circular
// arcs fitted across segment ends, ConnectRibbons of reconstruction/ribbons.h.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "reconstruction/circle_fit.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/polyline_overlap.h"
#include "reconstruction/ribbons.h"
#include "reconstruction/ribbons_internal.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

using detail::Curve;
using detail::IndexedRibbon;
using detail::RibbonVertexIndex;
using detail::SurfacePoint;
using detail::ToCoordinates;

namespace {

// Projections onto finished ribbons, each indexed when first asked for.
class RibbonProjector {
 public:
  explicit RibbonProjector(const std::vector<Ribbon>& ribbons)
      : ribbons_(ribbons), indices_(ribbons.size()) {}

  RibbonCoordinates Project(int r, const Eigen::Vector3f& p) {
    SurfacePoint q;
    if (!ProjectNear(r, p, &q)) return ProjectOntoRibbon(ribbons_[static_cast<size_t>(r)], p);
    return ToCoordinates(q, p, 0);
  }

  // Whether the segment's vertex order agrees with the ribbon's l direction
  // at the majority of its vertices near the ribbon (at its middle vertex
  // when none is).
  bool AlongRibbon(int r, const Curve& segment) {
    int votes = 0, voters = 0;
    for (size_t k = 0; k < segment.size(); ++k) {
      SurfacePoint q;
      if (!ProjectNear(r, segment[k], &q)) continue;
      votes += PolylineTangent(segment, k).dot(q.orientation) >= 0 ? 1 : -1;
      ++voters;
    }
    if (voters == 0) {
      const size_t middle = segment.size() / 2;
      return PolylineTangent(segment, middle).dot(Project(r, segment[middle]).orientation) >= 0;
    }
    return votes >= 0;
  }

 private:
  static constexpr double kSearchMm = 6.0;  // "near": a ribbon vertex this close

  bool ProjectNear(int r, const Eigen::Vector3f& p, SurfacePoint* q) {
    const Ribbon& ribbon = ribbons_[static_cast<size_t>(r)];
    auto& index = indices_[static_cast<size_t>(r)];
    if (index == nullptr) {
      index = std::make_unique<RibbonVertexIndex>(kSearchMm);
      for (int j = 0; j <= ribbon.width(); ++j)
        index->AddIsocurve(ribbon.isocurves[static_cast<size_t>(j)], j);
    }
    return IndexedRibbon{ribbon.isocurves, 0, *index}.Project(p, 0, ribbon.width(), kSearchMm, q);
  }

  const std::vector<Ribbon>& ribbons_;
  std::vector<std::unique_ptr<RibbonVertexIndex>> indices_;
};

// One end of a segment in a ribbon, with the circle fitted to its piece P.
struct SegmentEnd {
  int segment = -1, ribbon = -1;
  bool at_first = false;
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f outward = Eigen::Vector3f::Zero();  // leaving the segment at this end (unit)
  std::vector<Eigen::Vector3d> piece;  // the K vertices nearest the end, the end last
  Circle3 circle;                      // normal: counter-clockwise along `piece`
  bool fitted = false;
};

SegmentEnd MakeEnd(const Curve& points, int segment, int ribbon, bool at_first, int k_vertices) {
  SegmentEnd end;
  end.segment = segment;
  end.ribbon = ribbon;
  end.at_first = at_first;
  const size_t n = points.size();
  const size_t k = std::min(n, static_cast<size_t>(k_vertices));
  for (size_t m = 0; m < k; ++m) {
    const size_t from_end = k - 1 - m;  // the piece runs towards the end
    end.piece.push_back(points[at_first ? from_end : n - 1 - from_end].cast<double>());
  }
  end.position = points[at_first ? 0 : n - 1];
  const Eigen::Vector3f inner =
      points[at_first ? std::min<size_t>(2, n - 1) : n - 1 - std::min<size_t>(2, n - 1)];
  const Eigen::Vector3f out = end.position - inner;
  end.outward = out.norm() > 0 ? Eigen::Vector3f(out.normalized()) : out;
  end.fitted = std::isfinite(FitCircle3(end.piece, &end.circle));
  if (end.fitted) OrientByTraversal(end.piece, &end.circle);
  return end;
}

enum class Verdict { kLink, kDirection, kRms, kCurvature, kTorsion, kOverlap };
constexpr int kVerdicts = 6;

class ArcJudge {
 public:
  explicit ArcJudge(const ConnectionOptions& o)
      : o_(o),
        min_curvature_(1.0 / o.straight_radius_mm),
        min_normal_cos_(std::cos(o.max_normal_angle_deg * M_PI / 180.0)) {}

  // The tests of Sec. 6.1 on the arc from end a's segment to end b's, in the
  // order ConnectionSummary counts them.
  Verdict Judge(const SegmentEnd& a, const SegmentEnd& b, Circle3* joint, double* rms) const {
    if (!GapContinuesBoth(a, b)) return Verdict::kDirection;
    const double kappa_a = Curvature(a.circle), kappa_b = Curvature(b.circle);
    if (std::abs(kappa_a - kappa_b) / (kappa_a + kappa_b) > o_.max_curvature_ratio)
      return Verdict::kCurvature;
    // The arc runs along a's piece to its end, then along b's piece from its end: b's normal flips.
    const Circle3 piece_a = a.circle;
    Circle3 piece_b = b.circle;
    piece_b.normal = -piece_b.normal;
    if (!NormalsAgree(piece_a, piece_b)) return Verdict::kTorsion;
    std::vector<Eigen::Vector3d> arc = a.piece;
    arc.insert(arc.end(), b.piece.rbegin(), b.piece.rend());
    *rms = FitCircle3(arc, joint);
    if (!(*rms <= o_.max_rms_mm)) return Verdict::kRms;
    OrientByTraversal(arc, joint);
    if (SweepOverlap(arc, *joint) > o_.max_overlap) return Verdict::kOverlap;
    if (std::abs(2 * Curvature(*joint) - kappa_a - kappa_b) / (kappa_a + kappa_b) >
        o_.max_curvature_ratio) {
      return Verdict::kCurvature;
    }
    if (!NormalsAgree(*joint, piece_a) || !NormalsAgree(*joint, piece_b)) return Verdict::kTorsion;
    return Verdict::kLink;
  }

 private:
  double Curvature(const Circle3& c) const { return std::max(c.Curvature(), min_curvature_); }
  bool Straight(const Circle3& c) const { return c.radius > o_.straight_radius_mm; }
  bool NormalsAgree(const Circle3& x, const Circle3& y) const {
    return Straight(x) || Straight(y) || x.normal.dot(y.normal) >= min_normal_cos_;
  }
  bool GapContinuesBoth(const SegmentEnd& a, const SegmentEnd& b) const {
    constexpr float kCoincidentMm = 0.5f;
    const Eigen::Vector3f gap = b.position - a.position;
    if (gap.norm() < kCoincidentMm) return true;
    const Eigen::Vector3f towards_b = gap.normalized();
    return a.outward.dot(towards_b) > o_.min_gap_cos && b.outward.dot(-towards_b) > o_.min_gap_cos;
  }

  const ConnectionOptions& o_;
  double min_curvature_, min_normal_cos_;
};

// The verdicts on the pairs of one end with the ends after it.
struct EndVerdicts {
  struct Accepted {
    uint32_t partner;
    double rms_mm, radius_mm;
  };
  std::vector<Accepted> accepted;
  int64_t counts[kVerdicts] = {};  // per Verdict
};

void AddCounts(const EndVerdicts& v, ConnectionSummary* s) {
  const auto count = [&](Verdict which) { return v.counts[static_cast<int>(which)]; };
  for (int64_t c : v.counts) s->pairs_tried += c;
  s->links += count(Verdict::kLink);
  s->rejected_direction += count(Verdict::kDirection);
  s->rejected_rms += count(Verdict::kRms);
  s->rejected_curvature += count(Verdict::kCurvature);
  s->rejected_torsion += count(Verdict::kTorsion);
  s->rejected_overlap += count(Verdict::kOverlap);
}

// Every segment end in a ribbon, with its piece's circle (ends of segments
// with fewer than 3 vertices left out).
std::vector<SegmentEnd> FitEnds(const std::vector<StrandSegment>& segments,
                                const std::vector<int>& ribbon_of, const ConnectionOptions& o) {
  std::vector<std::pair<int, bool>> which;
  for (size_t seg = 0; seg < segments.size(); ++seg) {
    if (ribbon_of[seg] < 0 || segments[seg].points_mm.size() < 3) continue;
    which.emplace_back(static_cast<int>(seg), true);
    which.emplace_back(static_cast<int>(seg), false);
  }
  std::vector<SegmentEnd> ends(which.size());
  ParallelFor(which.size(), o.threads, [&] {
    return [&](size_t k) {
      const auto [seg, at_first] = which[k];
      ends[k] = MakeEnd(segments[static_cast<size_t>(seg)].points_mm, seg,
                        ribbon_of[static_cast<size_t>(seg)], at_first, o.fit_vertices);
    };
  });
  ends.erase(
      std::remove_if(ends.begin(), ends.end(), [](const SegmentEnd& e) { return !e.fitted; }),
      ends.end());
  return ends;
}

// The verdicts on every pair of ends in different ribbons within reach.
std::vector<EndVerdicts> JudgePairs(const std::vector<SegmentEnd>& ends,
                                    const ConnectionOptions& o) {
  std::vector<Eigen::Vector3f> positions;
  for (const SegmentEnd& e : ends) positions.push_back(e.position);
  const PointGrid grid(positions, o.max_end_gap_mm);
  const ArcJudge judge(o);
  std::vector<EndVerdicts> verdicts(ends.size());
  ParallelFor(ends.size(), o.threads, [&] {
    return [&](size_t e) {
      std::vector<uint32_t> partners;
      grid.ForEachWithin(positions[e], o.max_end_gap_mm, [&](uint32_t f, double) {
        if (f > e && ends[f].ribbon != ends[e].ribbon) partners.push_back(f);
      });
      std::sort(partners.begin(), partners.end());
      for (uint32_t f : partners) {
        Circle3 joint;
        double rms = 0;
        const Verdict verdict = judge.Judge(ends[e], ends[f], &joint, &rms);
        ++verdicts[e].counts[static_cast<int>(verdict)];
        if (verdict == Verdict::kLink) verdicts[e].accepted.push_back({f, rms, joint.radius});
      }
    };
  });
  return verdicts;
}

}  // namespace

Status ConnectionOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(max_end_gap_mm))
    return InvalidArgument("connection max_end_gap_mm must be positive");
  if (fit_vertices < 3) return InvalidArgument("connection fit_vertices must be at least 3");
  if (!positive(max_rms_mm)) return InvalidArgument("connection max_rms_mm must be positive");
  if (!positive(max_curvature_ratio))
    return InvalidArgument("connection max_curvature_ratio must be positive");
  if (!(max_normal_angle_deg >= 0 && max_normal_angle_deg <= 180)) {
    return InvalidArgument("connection max_normal_angle_deg must lie in 0..180");
  }
  if (!(max_overlap >= 0 && max_overlap <= 1))
    return InvalidArgument("connection max_overlap must lie in 0..1");
  if (!positive(straight_radius_mm))
    return InvalidArgument("connection straight_radius_mm must be positive");
  if (!(min_gap_cos >= -1 && min_gap_cos < 1))
    return InvalidArgument("connection min_gap_cos must lie in [-1, 1)");
  if (threads < 1) return InvalidArgument("connection threads must be at least 1");
  return Status::Ok();
}

std::vector<RibbonLink> ConnectRibbons(const std::vector<Ribbon>& ribbons,
                                       const std::vector<StrandSegment>& segments,
                                       const ConnectionOptions& options,
                                       ConnectionSummary* summary) {
  ConnectionSummary s;
  std::vector<int> ribbon_of(segments.size(), -1);
  for (size_t r = 0; r < ribbons.size(); ++r) {
    for (int seg : ribbons[r].segments) {
      if (seg >= 0 && static_cast<size_t>(seg) < segments.size() &&
          ribbon_of[static_cast<size_t>(seg)] < 0) {
        ribbon_of[static_cast<size_t>(seg)] = static_cast<int>(r);
      }
    }
  }
  const std::vector<SegmentEnd> ends = FitEnds(segments, ribbon_of, options);
  const std::vector<EndVerdicts> verdicts = JudgePairs(ends, options);
  RibbonProjector projector(ribbons);
  std::vector<int> along(segments.size(), -1);  // per segment, AlongRibbon once asked (0/1)
  const auto along_ribbon = [&](const SegmentEnd& e) {
    int& known = along[static_cast<size_t>(e.segment)];
    if (known < 0)
      known = projector.AlongRibbon(e.ribbon, segments[static_cast<size_t>(e.segment)].points_mm)
                  ? 1
                  : 0;
    return known == 1;
  };
  std::vector<RibbonLink> links;
  for (size_t e = 0; e < ends.size(); ++e) {
    AddCounts(verdicts[e], &s);
    for (const EndVerdicts::Accepted& accepted : verdicts[e].accepted) {
      RibbonLink link;
      for (int k = 0; k < 2; ++k) {
        const SegmentEnd& end = ends[k == 0 ? e : accepted.partner];
        link.ribbon[k] = end.ribbon;
        link.segment[k] = end.segment;
        link.link_point[k] = projector.Project(end.ribbon, end.position);
        link.at_first_vertex[k] = end.at_first;
        link.segment_along_ribbon[k] = along_ribbon(end);
      }
      link.rms_mm = accepted.rms_mm;
      link.radius_mm = accepted.radius_mm;
      links.push_back(link);
    }
  }
  if (summary != nullptr) *summary = s;
  return links;
}

}  // namespace hairrig
