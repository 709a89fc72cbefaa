#include "reconstruction/line_mvs.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/parallel.h"
#include "reconstruction/line_angle.h"
#include "reconstruction/orientation_map.h"

namespace hairrig {
namespace {

constexpr float kNoCost = 1.0f;

// Bilinear sample of a float map; false outside.
bool Sample(const cv::Mat1f& map, double u, double v, float* value) {
  if (!(u >= 0 && v >= 0 && u < map.cols - 1 && v < map.rows - 1)) return false;
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const float fx = static_cast<float>(u - x), fy = static_cast<float>(v - y);
  const float* r0 = map[y];
  const float* r1 = map[y + 1];
  *value =
      (r0[x] * (1 - fx) + r0[x + 1] * fx) * (1 - fy) + (r1[x] * (1 - fx) + r1[x + 1] * fx) * fy;
  return true;
}

// A neighbour as seen from the reference camera.
struct Neighbour {
  const MvsView* view = nullptr;
  Eigen::Matrix3d rotation;  // cam_n_from_cam_ref
  Eigen::Vector3d translation;
  std::array<double, CameraIntrinsics::kNumParams> params;
};

// The depths a cell's hypotheses may take.
struct DepthRange {
  float lo = 1, hi = 1;
  float Clamp(float d) const { return std::clamp(d, lo, hi); }
};

struct Hypothesis {
  float depth = 0;
  float tilt = 0;  // rad
  float cost = kNoCost;
};

class ReferenceSolver {
 public:
  ReferenceSolver(const std::vector<MvsView>& views, int reference,
                  const std::vector<int>& neighbours, double centre_depth,
                  const LineMvsOptions& options)
      : ref_(views[static_cast<size_t>(reference)]),
        options_(options),
        centre_depth_(centre_depth) {
    ref_params_ = ref_.camera.ToParams();
    const Rigid3d object_from_ref = ref_.cam_from_object.Inverse();
    for (int n : neighbours) {
      const Rigid3d n_from_ref = views[static_cast<size_t>(n)].cam_from_object * object_from_ref;
      neighbours_.push_back({&views[static_cast<size_t>(n)], n_from_ref.RotationMatrix(),
                             n_from_ref.translation,
                             views[static_cast<size_t>(n)].camera.ToParams()});
    }
    object_from_ref_rotation_ = object_from_ref.RotationMatrix();
  }

  LineDepthMap Solve(uint64_t seed) {
    const int cols = (ref_.grey.cols + options_.stride_px - 1) / options_.stride_px;
    const int rows = (ref_.grey.rows + options_.stride_px - 1) / options_.stride_px;
    LineDepthMap map;
    map.stride_px = options_.stride_px;
    map.depth_mm = cv::Mat1f(rows, cols, 0.f);
    map.cost = cv::Mat1f(rows, cols, kNoCost);
    map.direction = cv::Mat3f(rows, cols, cv::Vec3f(0, 0, 0));
    PrepareCells(rows, cols);
    std::mt19937_64 rng(seed);
    InitialiseRandomly(&rng);
    double depth_fraction = 0.25;  // of each cell's depth range
    double tilt_range = DegToRad(options_.max_tilt_deg) * 0.5;
    for (int it = 0; it < options_.iterations; ++it) {
      Sweep(it % 2 == 1, depth_fraction, tilt_range, &rng);
      depth_fraction *= 0.5;
      tilt_range *= 0.5;
    }
    for (size_t i = 0; i < cells_.size(); ++i) {
      const Cell& c = cells_[i];
      const Hypothesis& h = best_[i];
      if (h.cost >= kNoCost) continue;
      map.depth_mm(c.gy, c.gx) = h.depth;
      map.cost(c.gy, c.gx) = h.cost;
      const Eigen::Vector3d t = object_from_ref_rotation_ * Direction(c, h.tilt);
      map.direction(c.gy, c.gx) = cv::Vec3f(static_cast<float>(t.x()), static_cast<float>(t.y()),
                                            static_cast<float>(t.z()));
    }
    return map;
  }

 private:
  // A reference grid cell on hair: its ray and the in-image direction.
  struct Cell {
    int gx = 0, gy = 0;
    Eigen::Vector3d ray;     // (x, y, 1): normalised coordinates
    Eigen::Vector3d across;  // unit, perpendicular to the ray, along the image direction
    DepthRange range;
    float prior_mm = 0;    // the prior depth, 0 = none
    size_t first_ray = 0;  // its samples' rays (follow_orientation): sample_rays_[first_ray + k]
  };

  // The reference pixels of the samples through pixel (u, v), sample_step_px
  // apart in the image: along the streamline of the reference orientation map
  // through it (each step takes the map's orientation halfway along it, kept
  // pointing the way the last step went; a step where the map has none goes
  // straight on). Sample k of `along` is pixels[k], the middle one (u, v).
  void TraceStreamline(int u, int v, int along, std::array<Eigen::Vector2d, 31>* pixels) const {
    const int half = along / 2;
    const double step = options_.sample_step_px;
    const double a = DegToRad(ref_.orientation_deg(v, u));
    (*pixels)[static_cast<size_t>(half)] = Eigen::Vector2d(u, v);
    for (const int sign : {-1, 1}) {
      Eigen::Vector2d at(u, v), heading = sign * Eigen::Vector2d(std::cos(a), std::sin(a));
      for (int k = 1; k <= half; ++k) {
        const Eigen::Vector2d mid = at + 0.5 * step * heading;
        const int x = static_cast<int>(std::lround(mid.x())),
                  y = static_cast<int>(std::lround(mid.y()));
        if (x >= 0 && y >= 0 && x < ref_.orientation_deg.cols && y < ref_.orientation_deg.rows &&
            std::isfinite(ref_.orientation_deg(y, x))) {
          const double b = DegToRad(ref_.orientation_deg(y, x));
          const Eigen::Vector2d d(std::cos(b), std::sin(b));
          heading = d.dot(heading) >= 0 ? d : Eigen::Vector2d(-d);
        }
        at += step * heading;
        (*pixels)[static_cast<size_t>(half + sign * k)] = at;
      }
    }
  }

  // The rays (x, y, 1) of cell (u, v)'s samples appended to sample_rays_
  // (TraceStreamline); false, with nothing appended, when a sample leaves the
  // image or cannot be undistorted.
  bool AppendSampleRays(int u, int v) {
    std::array<Eigen::Vector2d, 31> pixels;
    const int along = options_.samples;
    TraceStreamline(u, v, along, &pixels);
    std::array<Eigen::Vector3d, 31> rays;
    for (int k = 0; k < along; ++k) {
      const Eigen::Vector2d& q = pixels[static_cast<size_t>(k)];
      if (!(q.x() >= 0 && q.y() >= 0 && q.x() <= ref_.grey.cols - 1 && q.y() <= ref_.grey.rows - 1))
        return false;
      const Result<Eigen::Vector2d> n = UndistortPixel(ref_.camera, q);
      if (!n.ok()) return false;
      rays[static_cast<size_t>(k)] = Eigen::Vector3d(n->x(), n->y(), 1.0);
    }
    sample_rays_.insert(sample_rays_.end(), rays.begin(), rays.begin() + along);
    return true;
  }

  void PrepareCells(int rows, int cols) {
    index_ = cv::Mat1i(rows, cols, -1);
    sample_rays_.clear();
    for (int gy = 0; gy < rows; ++gy) {
      for (int gx = 0; gx < cols; ++gx) {
        const int u = gx * options_.stride_px, v = gy * options_.stride_px;
        if (!ref_.hair(v, u)) continue;
        const float angle = ref_.orientation_deg(v, u);
        if (!std::isfinite(angle)) continue;
        const Result<Eigen::Vector2d> n0 = UndistortPixel(ref_.camera, Eigen::Vector2d(u, v));
        if (!n0.ok()) continue;
        Cell c;
        c.gx = gx;
        c.gy = gy;
        c.ray = Eigen::Vector3d(n0->x(), n0->y(), 1.0);
        // One pixel along the image direction, at the same depth (distortion
        // varies little over a pixel).
        const double a = DegToRad(angle);
        const Eigen::Vector3d along(std::cos(a) / ref_.camera.fx_px,
                                    std::sin(a) / ref_.camera.fy_px, 0.0);
        const Eigen::Vector3d r = c.ray.normalized();
        c.across = (along - along.dot(r) * r).normalized();
        c.prior_mm = ref_.prior_depth_mm.empty() ? 0.f : std::max(0.f, ref_.prior_depth_mm(v, u));
        c.range = RangeAt(c.prior_mm);
        c.first_ray = sample_rays_.size();
        if (options_.follow_orientation && !AppendSampleRays(u, v)) continue;
        index_(gy, gx) = static_cast<int>(cells_.size());
        cells_.push_back(c);
      }
    }
    best_.assign(cells_.size(), Hypothesis{});
  }

  DepthRange RangeAt(float prior) const {
    if (prior > 0) {
      return {std::max(1.f, prior - static_cast<float>(options_.prior_front_mm)),
              prior + static_cast<float>(options_.prior_behind_mm)};
    }
    return {static_cast<float>(std::max(1.0, centre_depth_ - options_.depth_margin_mm)),
            static_cast<float>(std::max(1.0, centre_depth_ + options_.depth_margin_mm))};
  }

  Eigen::Vector3d Direction(const Cell& c, double tilt) const {
    return std::cos(tilt) * c.across + std::sin(tilt) * c.ray.normalized();
  }

  void InitialiseRandomly(std::mt19937_64* rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_real_distribution<double> tilt(-DegToRad(options_.max_tilt_deg),
                                                DegToRad(options_.max_tilt_deg));
    for (size_t i = 0; i < cells_.size(); ++i) {
      const DepthRange& r = cells_[i].range;
      Hypothesis h{static_cast<float>(r.lo + unit(*rng) * (r.hi - r.lo)),
                   static_cast<float>(tilt(*rng)), kNoCost};
      h.cost = Cost(cells_[i], h.depth, h.tilt);
      best_[i] = h;
    }
  }

  // The hypotheses already scored during one cell's visit: a cost is a pure
  // function of (cell, depth, tilt), so a repeat would only recompute it.
  // A visit scores at most 12: the current best, 2 propagations from each of
  // 4 neighbours (Sweep) and 3 random refinements.
  struct Tried {
    std::array<std::pair<float, float>, 12> seen;
    int count = 0;
    bool Contains(float depth, float tilt) const {
      for (int k = 0; k < count; ++k)
        if (seen[static_cast<size_t>(k)] == std::make_pair(depth, tilt)) return true;
      return false;
    }
    void Add(float depth, float tilt) {
      if (count < static_cast<int>(seen.size())) seen[static_cast<size_t>(count++)] = {depth, tilt};
    }
  };

  void TryHypothesis(size_t i, float depth, float tilt, Tried* tried) {
    const double max_tilt = DegToRad(options_.max_tilt_deg);
    if (!std::isfinite(depth) || std::abs(tilt) > max_tilt) return;
    depth = cells_[i].range.Clamp(depth);
    if (tried->Contains(depth, tilt)) return;
    tried->Add(depth, tilt);
    const float cost = Cost(cells_[i], depth, tilt, best_[i].cost);
    if (cost < best_[i].cost) best_[i] = {depth, tilt, cost};
  }

  // One scan over the grid: each cell takes its scan-previous neighbours'
  // hypotheses, as the same depth and, where both have a prior, as the same
  // offset from the prior (the prior's surface follows the subject's slant),
  // then a random refinement.
  void Sweep(bool reverse, double depth_fraction, double tilt_range, std::mt19937_64* rng) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const int step = reverse ? -1 : 1;
    const int n = static_cast<int>(cells_.size());
    for (int k = reverse ? n - 1 : 0; k >= 0 && k < n; k += step) {
      const size_t i = static_cast<size_t>(k);
      const Cell& c = cells_[i];
      Tried tried;
      tried.Add(best_[i].depth, best_[i].tilt);
      const int dx[2] = {-step, 0}, dy[2] = {0, -step};
      for (int d = 0; d < 2; ++d) {
        for (int reach : {1, 3}) {
          const int x = c.gx + dx[d] * reach, y = c.gy + dy[d] * reach;
          if (x < 0 || y < 0 || x >= index_.cols || y >= index_.rows) continue;
          const int j = index_(y, x);
          if (j < 0) continue;
          const Hypothesis& hj = best_[static_cast<size_t>(j)];
          TryHypothesis(i, hj.depth, hj.tilt, &tried);
          const float prior_j = cells_[static_cast<size_t>(j)].prior_mm;
          if (c.prior_mm > 0 && prior_j > 0)
            TryHypothesis(i, c.prior_mm + (hj.depth - prior_j), hj.tilt, &tried);
        }
      }
      const Hypothesis h = best_[i];
      const double depth_range = depth_fraction * (c.range.hi - c.range.lo);
      TryHypothesis(i, static_cast<float>(h.depth + unit(*rng) * depth_range), h.tilt, &tried);
      TryHypothesis(i, h.depth, static_cast<float>(h.tilt + unit(*rng) * tilt_range), &tried);
      TryHypothesis(i, static_cast<float>(h.depth + unit(*rng) * depth_range),
                    static_cast<float>(h.tilt + unit(*rng) * tilt_range), &tried);
    }
  }

  // The segment's samples, computed once per hypothesis and shared by the
  // neighbours: points along it (and, for a single sample, a point a quarter
  // step further that gives the projected direction), made by MakeSamples;
  // for the photometric cost, a strip of three lines (sample k's are strip
  // points 3k .. 3k + 2, the middle one on the line) with the reference
  // view's grey values, made by MakeStrip (strip 0 until then).
  struct Samples {
    int along = 0, strip = 0;
    std::array<Eigen::Vector3d, 31> on_line;
    Eigen::Vector3d ahead;  // only for a single sample
    std::array<Eigen::Vector3d, 93> strip_points;
    std::array<float, 93> ref_grey{};
    bool strip_ok = true;
  };

  // The samples of a segment through the cell's ray at `depth` with `tilt`,
  // `step_mm` apart: on the straight line along `t` (Direction), or with
  // follow_orientation on the rays of the streamline's pixels, their depth
  // rising by tan(tilt) for each mm across the image, so that a straight
  // streamline gives the straight line of the same direction.
  void MakeSamples(const Cell& c, double depth, double tilt, double step_mm, Samples* s) const {
    const int half = options_.samples / 2;
    s->along = 2 * half + 1;
    const Eigen::Vector3d centre = c.ray * depth, t = Direction(c, tilt);
    const Eigen::Vector3d rise = std::tan(tilt) * step_mm * c.ray.normalized();
    for (int k = -half; k <= half; ++k) {
      s->on_line[static_cast<size_t>(k + half)] =
          options_.follow_orientation
              ? Eigen::Vector3d(sample_rays_[c.first_ray + static_cast<size_t>(k + half)] * depth +
                                static_cast<double>(k) * rise)
              : Eigen::Vector3d(centre + (k * step_mm) * t);
    }
    s->ahead = centre + 0.25 * step_mm * t;
    s->strip = 0;
    s->strip_ok = true;
  }

  // The photometric cost's strip of the samples MakeSamples made (with the
  // same cell, tilt and step), with the reference view's grey values;
  // strip_ok false when a strip point leaves the reference image.
  void MakeStrip(const Cell& c, double tilt, double step_mm, Samples* s) const {
    const Eigen::Vector3d t = Direction(c, tilt);
    for (int k = 0; k < s->along && s->strip_ok; ++k) {
      const Eigen::Vector3d tangent = options_.follow_orientation ? Tangent(*s, k, t) : t;
      const Eigen::Vector3d side = tangent.cross(c.ray.normalized()).normalized() * step_mm;
      for (int j = -1; j <= 1; ++j) {
        const Eigen::Vector3d p =
            s->on_line[static_cast<size_t>(k)] + static_cast<double>(j) * side;
        Eigen::Vector2d in_ref;
        ProjectCamPoint(ref_params_.data(), p.data(), in_ref.data());
        float a;
        if (!Sample(ref_.grey, in_ref.x(), in_ref.y(), &a)) {
          s->strip_ok = false;
          break;
        }
        s->strip_points[static_cast<size_t>(s->strip)] = p;
        s->ref_grey[static_cast<size_t>(s->strip++)] = a;
      }
    }
  }

  // Sample k's direction along the samples (from its neighbours), `fallback`
  // for a single sample.
  static Eigen::Vector3d Tangent(const Samples& s, int k, const Eigen::Vector3d& fallback) {
    if (s.along < 2) return fallback;
    const int from = std::max(0, k - 1), to = std::min(s.along - 1, k + 1);
    return s.on_line[static_cast<size_t>(to)] - s.on_line[static_cast<size_t>(from)];
  }

  // The mean of the `used` smallest of `costs[0 .. count)`, summed smallest
  // first.
  static float MeanOfSmallest(std::array<float, 16> costs, size_t count, size_t used) {
    std::partial_sort(costs.begin(), costs.begin() + static_cast<std::ptrdiff_t>(used),
                      costs.begin() + static_cast<std::ptrdiff_t>(count));
    float sum = 0;
    for (size_t k = 0; k < used; ++k) sum += costs[k];
    return sum / static_cast<float>(used);
  }

  // The cost of a segment through the cell's ray at `depth` with `tilt`: the
  // mean of the views_in_cost best neighbours' costs. A hypothesis that cannot
  // cost less than `beat` may stop early and return a value >= beat: the
  // orientation cost comes first, and a view's cost is at least half of it
  // (the photometric cost is >= 0), so the mean of those lower bounds, with
  // each view's exact cost put in as it is computed (cheapest bound first),
  // rules a hypothesis out before all its photometric costs are made. A
  // hypothesis that is not ruled out gets exactly the cost it gets without
  // `beat`.
  float Cost(const Cell& c, double depth, double tilt,
             float beat = std::numeric_limits<float>::infinity()) const {
    // Samples spaced `sample_step_px` as the reference view sees them.
    const double step_mm = options_.sample_step_px * depth / ref_.camera.fx_px;
    Samples samples;
    MakeSamples(c, depth, tilt, step_mm, &samples);
    const size_t count = neighbours_.size();
    const size_t used = std::min(count, static_cast<size_t>(options_.views_in_cost));
    std::array<ProjectedLine, 16> lines;
    std::array<float, 16> orientation_costs{};
    std::array<float, 16> view_costs{};  // a view's cost, or its lower bound until computed
    for (size_t v = 0; v < count; ++v) {
      ProjectLine(neighbours_[v], samples, &lines[v]);
      if (options_.cost == MvsCost::kPhotometric) continue;
      orientation_costs[v] = OrientationCost(neighbours_[v], lines[v]);
      view_costs[v] = options_.cost == MvsCost::kOrientation ? orientation_costs[v]
                                                             : 0.5f * orientation_costs[v];
    }
    if (options_.cost == MvsCost::kOrientation) return MeanOfSmallest(view_costs, count, used);
    std::array<size_t, 16> order;
    for (size_t v = 0; v < count; ++v) order[v] = v;
    std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count),
              [&](size_t a, size_t b) { return view_costs[a] < view_costs[b]; });
    for (size_t k = 0; k < count; ++k) {
      const float bound = MeanOfSmallest(view_costs, count, used);
      if (bound >= beat) return bound;
      if (k == 0) MakeStrip(c, tilt, step_mm, &samples);
      const size_t v = order[k];
      const float photometric_cost = PhotometricCost(neighbours_[v], samples, lines[v]);
      view_costs[v] = options_.cost == MvsCost::kPhotometric
                          ? photometric_cost
                          : 0.5f * (orientation_costs[v] + photometric_cost);
    }
    return MeanOfSmallest(view_costs, count, used);
  }

  bool ProjectInto(const Neighbour& nb, const Eigen::Vector3d& p_ref, Eigen::Vector2d* uv) const {
    const Eigen::Vector3d p = nb.rotation * p_ref + nb.translation;
    if (p.z() <= 1.0) return false;
    ProjectCamPoint(nb.params.data(), p.data(), uv->data());
    return true;
  }

  // The segment's samples as a neighbour sees them, and, for the orientation
  // cost, the direction of their line at each, in degrees in [0, 180) (NaN
  // when it cannot be told). With follow_orientation it runs from the sample
  // before to the sample after (one side at the ends); the straight segment's
  // projection is straight up to the lens distortion, which turns it by a
  // negligible angle over a few pixels, so its end-to-end direction serves
  // every sample.
  struct ProjectedLine {
    // Written by ProjectLine for the first `along` samples (left uninitialised:
    // Cost keeps one per neighbour).
    std::array<Eigen::Vector2d, 31> uv;
    std::array<bool, 31> ok;
    std::array<double, 31> direction_deg;
    int along = 0;
  };

  static double LineAngleDeg(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
    return hairrig::LineAngleDeg(to.x() - from.x(), to.y() - from.y());
  }

  void ProjectLine(const Neighbour& nb, const Samples& s, ProjectedLine* line) const {
    line->along = s.along;
    for (int k = 0; k < s.along; ++k) {
      const size_t i = static_cast<size_t>(k);
      line->ok[i] = ProjectInto(nb, s.on_line[i], &line->uv[i]);
    }
    if (options_.cost == MvsCost::kPhotometric) return;
    constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
    if (s.along == 1) {
      Eigen::Vector2d ahead;
      line->direction_deg[0] = line->ok[0] && ProjectInto(nb, s.ahead, &ahead)
                                   ? LineAngleDeg(line->uv[0], ahead)
                                   : kUnknown;
    } else if (!options_.follow_orientation) {
      const size_t last = static_cast<size_t>(s.along - 1);
      const double chord =
          line->ok[0] && line->ok[last] ? LineAngleDeg(line->uv[0], line->uv[last]) : kUnknown;
      std::fill_n(line->direction_deg.begin(), s.along, chord);
    } else {
      for (int k = 0; k < s.along; ++k) {
        const size_t from = static_cast<size_t>(std::max(0, k - 1)),
                     to = static_cast<size_t>(std::min(s.along - 1, k + 1));
        line->direction_deg[static_cast<size_t>(k)] =
            line->ok[from] && line->ok[to] ? LineAngleDeg(line->uv[from], line->uv[to]) : kUnknown;
      }
    }
  }

  float OrientationCost(const Neighbour& nb, const ProjectedLine& line) const {
    const int along = line.along;
    float sum = 0;
    const double truncation = options_.orientation_truncation_deg;
    for (int k = 0; k < along; ++k) {
      if (!line.ok[static_cast<size_t>(k)] ||
          !std::isfinite(line.direction_deg[static_cast<size_t>(k)])) {
        sum += 1;
        continue;
      }
      const Eigen::Vector2d& a = line.uv[static_cast<size_t>(k)];
      // The nearest pixel (floor of x + 0.5: std::lround is a libm call).
      const double fx = std::floor(a.x() + 0.5), fy = std::floor(a.y() + 0.5);
      if (!(fx >= 0 && fy >= 0 && fx < nb.view->hair.cols && fy < nb.view->hair.rows)) {
        sum += 1;
        continue;
      }
      const int x = static_cast<int>(fx), y = static_cast<int>(fy);
      if (!nb.view->hair(y, x)) {
        sum += 1;
        continue;
      }
      const float seen = nb.view->orientation_deg(y, x);
      if (!std::isfinite(seen)) {
        sum += 1;
        continue;
      }
      const double diff = LineAngleDifferenceDeg(line.direction_deg[static_cast<size_t>(k)], seen);
      sum += static_cast<float>(std::min(diff, truncation) / truncation);
    }
    return sum / static_cast<float>(along);
  }

  float PhotometricCost(const Neighbour& nb, const Samples& s, const ProjectedLine& line) const {
    if (!s.strip_ok || s.strip == 0) return kNoCost;
    double sr = 0, sn = 0, srr = 0, snn = 0, srn = 0;
    for (int i = 0; i < s.strip; ++i) {
      Eigen::Vector2d in_n;
      float b;
      const bool on_line = i % 3 == 1;
      const bool projected = on_line
                                 ? line.ok[static_cast<size_t>(i / 3)]
                                 : ProjectInto(nb, s.strip_points[static_cast<size_t>(i)], &in_n);
      if (on_line && projected) in_n = line.uv[static_cast<size_t>(i / 3)];
      if (!projected || !Sample(nb.view->grey, in_n.x(), in_n.y(), &b)) {
        return kNoCost;
      }
      const double a = s.ref_grey[static_cast<size_t>(i)];
      sr += a;
      sn += b;
      srr += a * a;
      snn += double(b) * b;
      srn += a * b;
    }
    const double count = s.strip;
    const double var_r = srr - sr * sr / count, var_n = snn - sn * sn / count;
    if (var_r < 1e-6 * count || var_n < 1e-6 * count) return kNoCost;
    const double ncc = (srn - sr * sn / count) / std::sqrt(var_r * var_n);
    return static_cast<float>((1.0 - std::clamp(ncc, -1.0, 1.0)) * 0.5);
  }

  const MvsView& ref_;
  const LineMvsOptions& options_;
  double centre_depth_;
  std::array<double, CameraIntrinsics::kNumParams> ref_params_{};
  std::vector<Neighbour> neighbours_;
  Eigen::Matrix3d object_from_ref_rotation_;
  std::vector<Cell> cells_;
  std::vector<Eigen::Vector3d> sample_rays_;  // follow_orientation: options_.samples a cell
  std::vector<Hypothesis> best_;
  cv::Mat1i index_;
};

Eigen::Vector3d ViewingDirection(const MvsView& v) {
  return v.cam_from_object.rotation.conjugate() * Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d CameraCentre(const MvsView& v) { return v.cam_from_object.Inverse().translation; }

// The point closest to the rays through each view's hair centroid (least squares).
Result<Eigen::Vector3d> SubjectCentre(const std::vector<MvsView>& views) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const MvsView& v : views) {
    const cv::Moments m = cv::moments(v.hair, true);
    if (m.m00 < 1) continue;
    const Result<Eigen::Vector2d> n =
        UndistortPixel(v.camera, Eigen::Vector2d(m.m10 / m.m00, m.m01 / m.m00));
    if (!n.ok()) continue;
    const Eigen::Vector3d d =
        (v.cam_from_object.rotation.conjugate() * Eigen::Vector3d(n->x(), n->y(), 1)).normalized();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * CameraCentre(v);
  }
  if (std::abs(a.determinant()) < 1e-9)
    return FailedPrecondition("the views' hair does not meet in one place");
  return Eigen::Vector3d(a.ldlt().solve(b));
}

}  // namespace

Status LineMvsOptions::Check() const {
  if (stride_px < 1 || stride_px > 8) return InvalidArgument("mvs stride_px must be in 1..8");
  if (neighbours < 1 || neighbours > 16) return InvalidArgument("mvs neighbours must be in 1..16");
  if (views_in_cost < 1 || views_in_cost > neighbours)
    return InvalidArgument("mvs views_in_cost must be in 1..neighbours");
  if (!(min_baseline_deg >= 0 && min_baseline_deg < max_baseline_deg && max_baseline_deg <= 180)) {
    return InvalidArgument(
        "mvs baselines must satisfy 0 <= min_baseline_deg < max_baseline_deg <= 180");
  }
  if (iterations < 1) return InvalidArgument("mvs iterations must be at least 1");
  if (samples < 1 || samples % 2 == 0 || samples > 31)
    return InvalidArgument("mvs samples must be odd, 1..31");
  if (!(sample_step_px > 0)) return InvalidArgument("mvs sample_step_px must be positive");
  if (!(orientation_truncation_deg > 0 && orientation_truncation_deg <= 90)) {
    return InvalidArgument("mvs orientation_truncation_deg must be in (0, 90]");
  }
  if (!(max_tilt_deg > 0 && max_tilt_deg < 90))
    return InvalidArgument("mvs max_tilt_deg must be in (0, 90)");
  if (!(depth_margin_mm > 0)) return InvalidArgument("mvs depth_margin_mm must be positive");
  if (!(prior_front_mm >= 0 && prior_behind_mm > 0 && prior_front_mm + prior_behind_mm < 1000))
    return InvalidArgument(
        "mvs prior_front_mm must be >= 0 and prior_behind_mm > 0 (their sum under 1000)");
  if (threads < 1) return InvalidArgument("mvs threads must be at least 1");
  return Status::Ok();
}

std::vector<int> NeighbourViews(const std::vector<MvsView>& views, int reference,
                                const LineMvsOptions& options) {
  const Eigen::Vector3d d_ref = ViewingDirection(views[static_cast<size_t>(reference)]);
  std::vector<std::pair<double, int>> candidates;
  for (size_t n = 0; n < views.size(); ++n) {
    if (static_cast<int>(n) == reference) continue;
    const double angle =
        RadToDeg(std::acos(std::clamp(d_ref.dot(ViewingDirection(views[n])), -1.0, 1.0)));
    if (angle >= options.min_baseline_deg && angle <= options.max_baseline_deg) {
      candidates.push_back({angle, static_cast<int>(n)});
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<int> out;
  for (size_t k = 0; k < candidates.size() && static_cast<int>(k) < options.neighbours; ++k)
    out.push_back(candidates[k].second);
  return out;
}

Result<std::vector<LineDepthMap>> ComputeLineDepthMaps(const std::vector<MvsView>& views,
                                                       const LineMvsOptions& options,
                                                       const MvsProgress& progress) {
  HR_RETURN_IF_ERROR(options.Check());
  if (views.size() < 2) return InvalidArgument("multi-view stereo needs at least two views");
  for (size_t v = 0; v < views.size(); ++v) {
    const MvsView& view = views[v];
    const cv::Size size(view.camera.width_px, view.camera.height_px);
    if (view.grey.size() != size || view.orientation_deg.size() != size ||
        view.hair.size() != size ||
        (!view.prior_depth_mm.empty() && view.prior_depth_mm.size() != size)) {
      return InvalidArgument("mvs view " + std::to_string(v) +
                             ": its maps are not the camera's size");
    }
  }
  std::vector<std::vector<int>> neighbours(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    neighbours[v] = NeighbourViews(views, static_cast<int>(v), options);
    if (static_cast<int>(neighbours[v].size()) < options.views_in_cost) {
      return FailedPrecondition("view " + std::to_string(v) + " has " +
                                std::to_string(neighbours[v].size()) + " neighbours within " +
                                std::to_string(options.min_baseline_deg) + "-" +
                                std::to_string(options.max_baseline_deg) + " deg; it needs " +
                                std::to_string(options.views_in_cost));
    }
  }
  HR_ASSIGN_OR_RETURN(const Eigen::Vector3d centre, SubjectCentre(views));
  std::vector<LineDepthMap> maps(views.size());
  std::atomic<int> done{0};
  ParallelFor(views.size(), options.threads, [&] {
    return [&](size_t v) {
      const double centre_depth = (views[v].cam_from_object * centre).z();
      ReferenceSolver solver(views, static_cast<int>(v), neighbours[v], centre_depth, options);
      maps[v] = solver.Solve(0x9e3779b97f4a7c15ull * (v + 1));
      maps[v].neighbours = neighbours[v];
      const int finished = ++done;
      if (progress) progress(finished, static_cast<int>(views.size()));
    };
  });
  return maps;
}

}  // namespace hairrig
