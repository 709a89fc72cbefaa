#include "reconstruction/wisps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <utility>

#include "reconstruction/interior_field.h"
#include "reconstruction/scalp_distance.h"
#include "reconstruction/scalp_guide.h"
#include "reconstruction/strand_segments.h"
#include "reconstruction/wisp_attachment.h"
#include "reconstruction/wisp_grid.h"

namespace hairrig {

namespace {

// At most this many interior strands are tried per interior wisp asked for.
constexpr int kInteriorAttemptsPerWisp = 4;
// A transition follows the points whose direction lies within acos(this) of
// its straight line (as Sec. 5.1's T_o: a wisp crossing the gap does not steer it).
constexpr double kTransitionNeighbourCos = 0.5;

// Whether the link's fitted end is the root-ward end of its segment in the
// ribbon on `side`: a strand coming through the link enters that ribbon
// there; at the tip-ward end it leaves it.
bool EntersAt(const RibbonLink& link, int side) {
  return link.at_first_vertex[side] == link.segment_along_ribbon[side];
}

int RoundedIndex(float l, int last) {
  return std::clamp(static_cast<int>(std::lround(l)), 0, last);
}

// Eq. 9: w in the current ribbon mapped to the predecessor's width [0, to_width].
double Stitch(double w, double from_w, double to_w, int to_width) {
  return std::clamp(w - from_w + to_w, 0.0, static_cast<double>(to_width));
}

// Eq. 10 over the span of the wisp's isocurves in the current ribbon (the
// paper's [0, W] for a wisp still on its first ribbon); 0 for a span of 0.
double StitchDistortion(const std::vector<double>& widths, double from_w, double to_w,
                        int to_width) {
  const auto [low, high] = std::minmax_element(widths.begin(), widths.end());
  const double span = *high - *low;
  if (span <= 0) return 0;
  return 1 - (Stitch(*high, from_w, to_w, to_width) - Stitch(*low, from_w, to_w, to_width)) / span;
}

// The orientation term's directions for a transition of `intervals` edges
// from a to b: the points' orientation (at the transitions' larger sigma) at
// the middle of each edge of the straight line, signed along it; the line's
// direction where no compatible point is near.
std::vector<Eigen::Vector3f> TransitionDirections(const PointOrientationField& field,
                                                  const Eigen::Vector3f& a,
                                                  const Eigen::Vector3f& b, int intervals) {
  const Eigen::Vector3f line = (b - a).normalized();
  std::vector<Eigen::Vector3f> directions(static_cast<size_t>(intervals), line);
  for (int k = 0; k < intervals; ++k) {
    const float share = (static_cast<float>(k) + 0.5f) / static_cast<float>(intervals);
    Eigen::Vector3f orientation;
    if (field.At(a + share * (b - a), line, kTransitionNeighbourCos, 1, &orientation)) {
      directions[static_cast<size_t>(k)] = orientation;
    }
  }
  return directions;
}

// The inner vertices (a and b excluded) of the transition from a to b: the
// straight line at directions.size() edges, smoothed by Eq. 3 with its edges
// along `directions` (each as long as the line's) and a, b and the vertices
// before a and after b (each optional) kept.
std::vector<Eigen::Vector3f> SmoothTransition(const Eigen::Vector3f* before,
                                              const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                              const Eigen::Vector3f* after,
                                              const std::vector<Eigen::Vector3f>& directions,
                                              const WispOptions& o) {
  const int intervals = static_cast<int>(directions.size());
  const float edge_length = (b - a).norm() / static_cast<float>(intervals);
  std::vector<Eigen::Vector3f> line;
  PolylineSmoothing smoothing;
  smoothing.alpha_position = o.smooth_position;
  smoothing.alpha_orientation = o.smooth_orientation;
  smoothing.alpha_curvature = o.smooth_curvature;
  if (before != nullptr) {
    line.push_back(*before);
    smoothing.edges.push_back(a - *before);
    smoothing.fixed.push_back(1);
  }
  for (int k = 0; k <= intervals; ++k) {
    line.push_back(a + (b - a) * (static_cast<float>(k) / static_cast<float>(intervals)));
    if (k < intervals) smoothing.edges.push_back(directions[static_cast<size_t>(k)] * edge_length);
    smoothing.fixed.push_back(k == 0 || k == intervals ? 1 : 0);
  }
  if (after != nullptr) {
    line.push_back(*after);
    smoothing.edges.push_back(*after - b);
    smoothing.fixed.push_back(1);
  }
  const std::vector<Eigen::Vector3f> smooth = SmoothPolyline(line, smoothing);
  const size_t first_inner = before != nullptr ? 2 : 1;
  return std::vector<Eigen::Vector3f>(
      smooth.begin() + static_cast<std::ptrdiff_t>(first_inner),
      smooth.begin() + static_cast<std::ptrdiff_t>(first_inner) + intervals - 1);
}

struct ConnectedWisp {
  Isocurves isocurves;
  std::vector<int> ribbons;
};

// A feasible link for connecting up: the strand enters the ribbon on `side`
// (the current one, or one overlapping it) and comes from the other.
struct LinkCandidate {
  int link, side;
  double distance2;  // of its link point on `side` to the wisp's start on the current ribbon
};

struct Predecessor {
  int ribbon = -1;
  RibbonCoordinates on_current,
      on_predecessor;  // the chosen link's points, in the current's and R*'s parameters
};

// Sec. 6.3's connecting up, one wisp per starting ribbon.
class RibbonConnector {
 public:
  // `rootward` (may be null: no progress rule) ranks points by H + zeta.
  RibbonConnector(const std::vector<Ribbon>& ribbons, const std::vector<RibbonLink>& links,
                  const PointOrientationField& bridge_field, const ScalpDistance* rootward,
                  const WispOptions& options);

  // The wisp started from ribbon `start`; marks the ribbons each connection
  // joins in `connected` and counts the connections.
  ConnectedWisp Connect(int start, std::vector<uint8_t>* connected, int64_t* connections);

 private:
  bool FindPredecessor(int current, const std::vector<double>& widths,
                       const std::vector<int>& in_wisp, Predecessor* found);
  // Eq. 8 then Eq. 10 among the candidates; `direct`: their side is the
  // current ribbon (else a ribbon overlapping it, whose link points are
  // projected onto the current one).
  bool Choose(int current, const std::vector<double>& widths, std::vector<LinkCandidate> candidates,
              bool direct, Predecessor* found);
  // Psi of the links: the smaller number of distinct segments on either side.
  int Strength(const std::vector<LinkCandidate>& group) const;
  // H + zeta at p (Eq. 5's ranking from the root).
  double RootRank(const Eigen::Vector3f& p) const;
  // eta(a, b) and whether their directions are compatible (cached).
  const std::pair<double, bool>& Overlap(int a, int b);

  // Vertices `end` down to `begin` of the isocurves at `widths`, appended to
  // each tip-first isocurve.
  static void AppendBackwards(const Isocurves& ribbon, const std::vector<double>& widths, int begin,
                              int end, Isocurves* tip_first);
  // The transition from R* (vertex `from_index` at `from_widths`) to the
  // current ribbon (vertex `to_begin` at `to_widths`), its inner vertices
  // appended backwards.
  void AppendTransition(const Isocurves& from, const std::vector<double>& from_widths,
                        int from_index, const Isocurves& to, const std::vector<double>& to_widths,
                        int to_begin, int to_end, Isocurves* tip_first) const;

  const std::vector<Ribbon>& ribbons_;
  const std::vector<RibbonLink>& links_;
  const PointOrientationField& bridge_field_;
  const WispOptions& o_;
  const ScalpDistance* rootward_;
  std::vector<double> root_rank_;             // per ribbon: H + zeta of its centre's root end
  std::vector<Eigen::Vector3f> link_points_;  // 2 k + side: links_[k].link_point[side].closest
  std::unique_ptr<PointGrid> link_grid_;
  std::map<std::pair<int, int>, std::pair<double, bool>> overlaps_;
};

RibbonConnector::RibbonConnector(const std::vector<Ribbon>& ribbons,
                                 const std::vector<RibbonLink>& links,
                                 const PointOrientationField& bridge_field,
                                 const ScalpDistance* rootward, const WispOptions& options)
    : ribbons_(ribbons),
      links_(links),
      bridge_field_(bridge_field),
      o_(options),
      rootward_(rootward) {
  if (rootward_ && o_.min_progress_mm >= 0) {
    for (const Ribbon& r : ribbons_)
      root_rank_.push_back(r.isocurves.empty() ? 0.0 : RootRank(r.center().front()));
  }
  link_points_.reserve(2 * links.size());
  for (const RibbonLink& link : links) {
    link_points_.push_back(link.link_point[0].closest);
    link_points_.push_back(link.link_point[1].closest);
  }
  link_grid_ = std::make_unique<PointGrid>(link_points_, o_.link_distance_mm);
}

double RibbonConnector::RootRank(const Eigen::Vector3f& p) const {
  return static_cast<double>(p.dot(o_.down)) + (*rootward_)(p);
}

const std::pair<double, bool>& RibbonConnector::Overlap(int a, int b) {
  const std::pair<int, int> key(std::min(a, b), std::max(a, b));
  const auto known = overlaps_.find(key);
  if (known != overlaps_.end()) return known->second;
  bool compatible = false;
  const double eta =
      RibbonOverlap(ribbons_[key.first], ribbons_[key.second], o_.overlap_mm, &compatible);
  return overlaps_.emplace(key, std::make_pair(eta, compatible)).first->second;
}

int RibbonConnector::Strength(const std::vector<LinkCandidate>& group) const {
  std::vector<int> entered, left;
  for (const LinkCandidate& c : group) {
    entered.push_back(links_[c.link].segment[c.side]);
    left.push_back(links_[c.link].segment[1 - c.side]);
  }
  for (std::vector<int>* segments : {&entered, &left}) {
    std::sort(segments->begin(), segments->end());
    segments->erase(std::unique(segments->begin(), segments->end()), segments->end());
  }
  return static_cast<int>(std::min(entered.size(), left.size()));
}

bool RibbonConnector::FindPredecessor(int current, const std::vector<double>& widths,
                                      const std::vector<int>& in_wisp, Predecessor* found) {
  const Eigen::Vector3f start =
      IsocurvePoint(ribbons_[current].isocurves, widths[widths.size() / 2], 0);
  const double reach2 = o_.link_distance_mm * o_.link_distance_mm;
  const double start_rank = root_rank_.empty() ? 0.0 : RootRank(start);
  std::vector<LinkCandidate> direct, via_overlap;
  link_grid_->ForEachWithin(start, o_.link_distance_mm, [&](uint32_t id, double d2) {
    if (d2 >= reach2) return;
    const int k = static_cast<int>(id / 2), side = static_cast<int>(id % 2);
    const RibbonLink& link = links_[static_cast<size_t>(k)];
    const int entered = link.ribbon[side], predecessor = link.ribbon[1 - side];
    if (predecessor == current || predecessor == entered) return;
    if (ribbons_[predecessor].length() < 1 || ribbons_[entered].length() < 1) return;
    if (std::find(in_wisp.begin(), in_wisp.end(), predecessor) != in_wisp.end()) return;
    if (!root_rank_.empty() &&
        root_rank_[static_cast<size_t>(predecessor)] > start_rank - o_.min_progress_mm)
      return;
    if (!EntersAt(link, side) || EntersAt(link, 1 - side)) return;
    (entered == current ? direct : via_overlap).push_back({k, side, d2});
  });
  if (Choose(current, widths, direct, true, found)) return true;
  via_overlap.erase(std::remove_if(via_overlap.begin(), via_overlap.end(),
                                   [&](const LinkCandidate& c) {
                                     const std::pair<double, bool>& overlap =
                                         Overlap(current, links_[c.link].ribbon[c.side]);
                                     return !(overlap.first > 0 && overlap.second);
                                   }),
                    via_overlap.end());
  return Choose(current, widths, via_overlap, false, found);
}

bool RibbonConnector::Choose(int current, const std::vector<double>& widths,
                             std::vector<LinkCandidate> candidates, bool direct,
                             Predecessor* found) {
  const auto predecessor_of = [&](const LinkCandidate& c) {
    return links_[c.link].ribbon[1 - c.side];
  };
  std::sort(candidates.begin(), candidates.end(),
            [&](const LinkCandidate& a, const LinkCandidate& b) {
              return std::make_pair(predecessor_of(a), a.link) <
                     std::make_pair(predecessor_of(b), b.link);
            });
  struct Group {
    std::vector<LinkCandidate> links;
    int strength = 0;
  };
  std::vector<Group> groups;
  for (size_t begin = 0, end = 0; begin < candidates.size(); begin = end) {
    while (end < candidates.size() &&
           predecessor_of(candidates[end]) == predecessor_of(candidates[begin]))
      ++end;
    Group group;
    group.links.assign(candidates.begin() + static_cast<std::ptrdiff_t>(begin),
                       candidates.begin() + static_cast<std::ptrdiff_t>(end));
    group.strength = Strength(group.links);
    groups.push_back(std::move(group));
  }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) {
    return std::make_pair(a.strength, a.links.size()) > std::make_pair(b.strength, b.links.size());
  });
  for (const Group& group : groups) {
    const int predecessor = predecessor_of(group.links[0]);
    if (Overlap(current, predecessor).first > o_.max_connect_overlap) continue;  // a local cycle
    double best_distortion = std::numeric_limits<double>::max(), best_distance2 = 0;
    for (const LinkCandidate& c : group.links) {
      const RibbonLink& link = links_[static_cast<size_t>(c.link)];
      const RibbonCoordinates on_current =
          direct ? link.link_point[c.side]
                 : ProjectOntoRibbon(ribbons_[current], link.link_point[c.side].closest);
      const RibbonCoordinates& on_predecessor = link.link_point[1 - c.side];
      const double distortion =
          StitchDistortion(widths, on_current.w, on_predecessor.w, ribbons_[predecessor].width());
      if (distortion < best_distortion ||
          (distortion == best_distortion && c.distance2 < best_distance2)) {
        best_distortion = distortion, best_distance2 = c.distance2;
        *found = {predecessor, on_current, on_predecessor};
      }
    }
    return true;
  }
  return false;
}

void RibbonConnector::AppendBackwards(const Isocurves& ribbon, const std::vector<double>& widths,
                                      int begin, int end, Isocurves* tip_first) {
  for (size_t j = 0; j < widths.size(); ++j)
    for (int i = end; i >= begin; --i)
      (*tip_first)[j].push_back(IsocurvePoint(ribbon, widths[j], i));
}

void RibbonConnector::AppendTransition(const Isocurves& from,
                                       const std::vector<double>& from_widths, int from_index,
                                       const Isocurves& to, const std::vector<double>& to_widths,
                                       int to_begin, int to_end, Isocurves* tip_first) const {
  const size_t centre = from_widths.size() / 2;
  const Eigen::Vector3f centre_a = IsocurvePoint(from, from_widths[centre], from_index);
  const Eigen::Vector3f centre_b = IsocurvePoint(to, to_widths[centre], to_begin);
  const int intervals =
      std::max(1, static_cast<int>(std::ceil((centre_b - centre_a).norm() / o_.step_mm)));
  if (intervals < 2) return;  // the two ends are joined directly
  const std::vector<Eigen::Vector3f> directions =
      TransitionDirections(bridge_field_, centre_a, centre_b, intervals);
  for (size_t j = 0; j < from_widths.size(); ++j) {
    const Eigen::Vector3f before = IsocurvePoint(from, from_widths[j], std::max(from_index - 1, 0));
    const Eigen::Vector3f after = IsocurvePoint(to, to_widths[j], std::min(to_begin + 1, to_end));
    const std::vector<Eigen::Vector3f> inner = SmoothTransition(
        from_index > 0 ? &before : nullptr, IsocurvePoint(from, from_widths[j], from_index),
        IsocurvePoint(to, to_widths[j], to_begin), to_begin < to_end ? &after : nullptr, directions,
        o_);
    (*tip_first)[j].insert((*tip_first)[j].end(), inner.rbegin(), inner.rend());
  }
}

ConnectedWisp RibbonConnector::Connect(int start, std::vector<uint8_t>* connected,
                                       int64_t* connections) {
  ConnectedWisp wisp;
  wisp.ribbons = {start};
  std::vector<double> widths(static_cast<size_t>(ribbons_[start].width()) + 1);
  std::iota(widths.begin(), widths.end(), 0.0);
  Isocurves tip_first(widths.size());
  int current = start, end = ribbons_[start].length();
  Predecessor predecessor;
  while (FindPredecessor(current, widths, wisp.ribbons, &predecessor)) {
    const Ribbon& from = ribbons_[predecessor.ribbon];
    const int begin = RoundedIndex(predecessor.on_current.l, end);
    AppendBackwards(ribbons_[current].isocurves, widths, begin, end, &tip_first);
    std::vector<double> from_widths(widths.size());
    for (size_t j = 0; j < widths.size(); ++j) {
      from_widths[j] =
          Stitch(widths[j], predecessor.on_current.w, predecessor.on_predecessor.w, from.width());
    }
    const int from_index = RoundedIndex(predecessor.on_predecessor.l, from.length());
    AppendTransition(from.isocurves, from_widths, from_index, ribbons_[current].isocurves, widths,
                     begin, end, &tip_first);
    (*connected)[current] = (*connected)[predecessor.ribbon] = 1;
    ++*connections;
    widths = std::move(from_widths);
    current = predecessor.ribbon;
    end = from_index;
    wisp.ribbons.push_back(current);
  }
  AppendBackwards(ribbons_[current].isocurves, widths, 0, end, &tip_first);
  for (std::vector<Eigen::Vector3f>& isocurve : tip_first)
    std::reverse(isocurve.begin(), isocurve.end());
  wisp.isocurves = std::move(tip_first);
  return wisp;
}

size_t VertexCount(const Isocurves& grid) {
  return grid.size() * (grid.empty() ? 0 : grid[0].size());
}

// Outliers: wisps of one ribbon that no connection touched (unless it covers
// keep_lone_ribbon_segments segments or more).
int64_t RemoveOutliers(const std::vector<Ribbon>& ribbons, const std::vector<uint8_t>& connected,
                       const WispOptions& o, std::vector<ConnectedWisp>* wisps) {
  const auto outlier = [&](const ConnectedWisp& w) {
    if (w.ribbons.size() != 1 || connected[static_cast<size_t>(w.ribbons[0])]) return false;
    const size_t segments = ribbons[static_cast<size_t>(w.ribbons[0])].segments.size();
    return !(o.keep_lone_ribbon_segments > 0 &&
             segments >= static_cast<size_t>(o.keep_lone_ribbon_segments));
  };
  const size_t before = wisps->size();
  wisps->erase(std::remove_if(wisps->begin(), wisps->end(), outlier), wisps->end());
  return static_cast<int64_t>(before - wisps->size());
}

// Wisps whose every vertex lies within overlap_mm of a vertex of another
// remaining wisp, from the smallest up.
int64_t RemoveCovered(const WispOptions& o, std::vector<ConnectedWisp>* wisps) {
  std::vector<const Isocurves*> grids;
  for (const ConnectedWisp& w : *wisps) grids.push_back(&w.isocurves);
  const GridVertexIndex index(grids, o.overlap_mm);
  std::vector<size_t> order(wisps->size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return VertexCount(*grids[a]) < VertexCount(*grids[b]);
  });
  std::vector<uint8_t> removed(wisps->size(), 0);
  const double overlap2 = o.overlap_mm * o.overlap_mm;
  for (size_t k : order) {
    const auto overlapped = [&](const Eigen::Vector3f& v) {
      return index.points().AnyWithin(v, o.overlap_mm, [&](uint32_t vertex, double d2) {
        const uint32_t other = index.owner(vertex).grid;
        return d2 < overlap2 && other != k && !removed[other];
      });
    };
    const auto isocurve_overlapped = [&](const std::vector<Eigen::Vector3f>& isocurve) {
      return std::all_of(isocurve.begin(), isocurve.end(), overlapped);
    };
    removed[k] = std::all_of(grids[k]->begin(), grids[k]->end(), isocurve_overlapped) ? 1 : 0;
  }
  std::vector<ConnectedWisp> kept;
  for (size_t k = 0; k < wisps->size(); ++k)
    if (!removed[k]) kept.push_back(std::move((*wisps)[k]));
  const int64_t count = static_cast<int64_t>(wisps->size() - kept.size());
  *wisps = std::move(kept);
  return count;
}

Status CheckRibbonsAndLinks(const std::vector<Ribbon>& ribbons,
                            const std::vector<RibbonLink>& links) {
  for (size_t r = 0; r < ribbons.size(); ++r) {
    for (const std::vector<Eigen::Vector3f>& isocurve : ribbons[r].isocurves) {
      if (isocurve.size() != ribbons[r].isocurves[0].size()) {
        return InvalidArgument("ribbon " + std::to_string(r) + ": its isocurves differ in length");
      }
    }
  }
  const int count = static_cast<int>(ribbons.size());
  for (size_t k = 0; k < links.size(); ++k) {
    for (int side = 0; side < 2; ++side) {
      if (links[k].ribbon[side] < 0 || links[k].ribbon[side] >= count) {
        return InvalidArgument("ribbon link " + std::to_string(k) + " names ribbon " +
                               std::to_string(links[k].ribbon[side]) + " of " +
                               std::to_string(count));
      }
    }
  }
  return Status::Ok();
}

double BoundingDiagonal(const std::vector<OrientedPoint>& points) {
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), high = -low;
  for (const OrientedPoint& p : points)
    low = low.cwiseMin(p.position_mm), high = high.cwiseMax(p.position_mm);
  return static_cast<double>((high - low).norm());
}

// Sec. 6.3: every usable ribbon connected up, then outliers and covered wisps removed.
std::vector<ConnectedWisp> ConnectRibbonsIntoWisps(const std::vector<OrientedPoint>& points,
                                                   const std::vector<Ribbon>& ribbons,
                                                   const std::vector<RibbonLink>& links,
                                                   const HeadModel& head, const WispOptions& o,
                                                   WispSummary* s) {
  const PointOrientationField bridge_field(points, o.bridge_sigma_mm);
  const ScalpDistance rootward(&head);
  RibbonConnector connector(ribbons, links, bridge_field, &rootward, o);
  std::vector<uint8_t> connected(ribbons.size(), 0);
  std::vector<ConnectedWisp> wisps;
  for (size_t r = 0; r < ribbons.size(); ++r) {
    if (ribbons[r].isocurves.empty() || ribbons[r].length() < 1) continue;
    wisps.push_back(connector.Connect(static_cast<int>(r), &connected, &s->connections));
  }
  s->removed_outliers = RemoveOutliers(ribbons, connected, o, &wisps);
  s->removed_covered = RemoveCovered(o, &wisps);
  return wisps;
}

// Sec. 7.2: interior wisps towards points drawn among those far from the scalp.
int64_t AddInteriorWisps(const std::vector<OrientedPoint>& points, const ScalpGuide& guide,
                         const WispAttacher& attacher, const WispOptions& o, std::mt19937_64& rng,
                         std::vector<Wisp>* wisps) {
  std::vector<uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  int64_t made = 0;
  int attempts = 0;
  const int max_attempts = kInteriorAttemptsPerWisp * o.interior_wisps;
  for (size_t t = 0; t < order.size() && made < o.interior_wisps && attempts < max_attempts; ++t) {
    std::swap(order[t], order[std::uniform_int_distribution<size_t>(t, order.size() - 1)(rng)]);
    const Eigen::Vector3f& target = points[order[t]].position_mm;
    if (guide.AnySampleWithin(target, o.interior_min_scalp_distance_mm)) continue;
    ++attempts;
    Wisp wisp;
    if (!attacher.MakeInteriorWisp(target, rng, &wisp)) continue;
    wisps->push_back(std::move(wisp));
    ++made;
  }
  return made;
}

double CentreLength(const Wisp& wisp) {
  double length = 0;
  const std::vector<Eigen::Vector3f>& centre = wisp.center();
  for (size_t i = 1; i < centre.size(); ++i) length += (centre[i] - centre[i - 1]).norm();
  return length;
}

}  // namespace

Status WispOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  const auto share = [](double v) { return v >= 0 && v <= 1; };
  if (!positive(link_distance_mm)) return InvalidArgument("wisp link_distance_mm must be positive");
  if (!share(max_connect_overlap))
    return InvalidArgument("wisp max_connect_overlap must lie in 0..1");
  if (!positive(overlap_mm)) return InvalidArgument("wisp overlap_mm must be positive");
  if (!positive(step_mm)) return InvalidArgument("wisp step_mm must be positive");
  if (!positive(bridge_sigma_mm)) return InvalidArgument("wisp bridge_sigma_mm must be positive");
  if (!(interior_weight >= 0)) return InvalidArgument("wisp interior_weight must be non-negative");
  if (!positive(voxel_mm)) return InvalidArgument("wisp voxel_mm must be positive");
  if (!(interior_min_scalp_distance_mm >= 0))
    return InvalidArgument("wisp interior_min_scalp_distance_mm must be non-negative");
  if (interior_wisps < 0) return InvalidArgument("wisp interior_wisps must be non-negative");
  if (interior_width < 0 || interior_width > 1000)
    return InvalidArgument("wisp interior_width must lie in 0..1000");
  if (!share(taper_start)) return InvalidArgument("wisp taper_start must lie in 0..1");
  if (!(std::abs(down.norm() - 1) < 1e-3))
    return InvalidArgument("wisp down must be a unit vector");
  if (!positive(spacing_mm)) return InvalidArgument("wisp spacing_mm must be positive");
  if (!share(cover_cos)) return InvalidArgument("wisp cover_cos must lie in 0..1");
  if (!(smooth_position > 0) || !(smooth_orientation >= 0) || !(smooth_curvature >= 0)) {
    return InvalidArgument(
        "wisp smoothing weights: position must be positive, the others non-negative");
  }
  if (!(head_clearance_mm >= 0))
    return InvalidArgument("wisp head_clearance_mm must be non-negative");
  if (!(root_jitter_mm >= 0)) return InvalidArgument("wisp root_jitter_mm must be non-negative");
  if (!share(root_width_share)) return InvalidArgument("wisp root_width_share must lie in 0..1");
  if (!share(interior_truncate_level))
    return InvalidArgument("wisp interior_truncate_level must lie in 0..1");
  if (!positive(range_smoothness)) return InvalidArgument("wisp range_smoothness must be positive");
  if (!share(tip_range_share)) return InvalidArgument("wisp tip_range_share must lie in 0..1");
  if (keep_lone_ribbon_segments < 0)
    return InvalidArgument("wisp keep_lone_ribbon_segments must be non-negative");
  return Status::Ok();
}

Result<std::vector<Wisp>> BuildWisps(const std::vector<OrientedPoint>& points,
                                     const std::vector<Ribbon>& ribbons,
                                     const std::vector<RibbonLink>& links, const HeadModel& head,
                                     const WispOptions& o, WispSummary* summary) {
  HR_RETURN_IF_ERROR(o.Check());
  if (points.empty()) return InvalidArgument("wisps need the points (none given)");
  HR_RETURN_IF_ERROR(CheckRibbonsAndLinks(ribbons, links));
  const ScalpGuide guide(head, o.down);
  if (guide.empty())
    return InvalidArgument("the head has no scalp to attach wisps to (see head.scalp's hairline)");
  WispSummary s;
  std::vector<ConnectedWisp> connected =
      ConnectRibbonsIntoWisps(points, ribbons, links, head, o, &s);

  InteriorFieldOptions field_options;
  field_options.voxel_mm = o.voxel_mm;
  HR_ASSIGN_OR_RETURN(const InteriorField field, InteriorField::Build(points, head, field_options));
  const WispAttacher attacher(head, guide, field, o, BoundingDiagonal(points));
  std::mt19937_64 rng(o.seed);
  std::vector<Wisp> wisps;
  for (ConnectedWisp& c : connected) {
    Wisp wisp;
    wisp.isocurves = std::move(c.isocurves);
    wisp.ribbons = std::move(c.ribbons);
    if (!attacher.Attach(&wisp, rng)) {
      ++s.unattached;
      continue;
    }
    wisps.push_back(std::move(wisp));
  }
  s.interior = AddInteriorWisps(points, guide, attacher, o, rng, &wisps);
  s.covered_points = SetWispRanges(points, o, &wisps);
  SetWispNormals(head, &wisps);

  s.wisps = static_cast<int64_t>(wisps.size());
  double total_length = 0;
  for (const Wisp& wisp : wisps) {
    s.attached += wisp.attached ? 1 : 0;
    total_length += CentreLength(wisp);
  }
  s.mean_length_mm = wisps.empty() ? 0 : total_length / static_cast<double>(wisps.size());
  if (summary != nullptr) *summary = s;
  if (wisps.empty()) {
    return InvalidArgument("no wisp could be built: " + std::to_string(ribbons.size()) +
                           " ribbons, " + std::to_string(s.removed_outliers) +
                           " removed as outliers, " + std::to_string(s.removed_covered) +
                           " as covered, no interior wisp");
  }
  return wisps;
}

}  // namespace hairrig
