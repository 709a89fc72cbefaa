#include "sim_hw/wig.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/parallel.h"
#include "core/strand_io.h"
#include "core/transform.h"

namespace hairrig {
namespace {

// A root direction (unit, from the head centre) on the scalp of a head whose
// scene gives no scalp: above a minimum elevation and outside the face cone.
Eigen::Vector3d SampleScalpDirection(const WigOptions& o, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double min_sin = std::sin(DegToRad(o.scalp_min_elevation_deg));
  const double cos_face = std::cos(DegToRad(o.face_half_angle_deg));
  for (;;) {
    // Uniform on the sphere cap above the minimum elevation.
    const double z = min_sin + (1.0 - min_sin) * uniform(rng);
    const double phi = 2.0 * kPi * uniform(rng);
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Eigen::Vector3d d(s * std::cos(phi), s * std::sin(phi), z);
    // Leave the face free, except high on the forehead.
    if (d.dot(o.face_dir) > cos_face && z < 0.55) continue;
    return d;
  }
}

// Fibre length per unit of centreline length once the style's offset has
// grown in: a curl of radius r and pitch P winds 2 pi r sideways per P.
double FibreStretch(const WigOptions& o) {
  if (o.style != WigStyle::kCurly) return 1.0;
  return std::hypot(1.0, 2.0 * kPi * o.curl_radius_mm / o.curl_pitch_mm);
}

// The centreline step: a fibre segment of about segment_mm, and at least
// kPointsPerCurl points per turn of a curl (fewer alias it into a zigzag).
double CentrelineStep(const WigOptions& o) {
  constexpr double kPointsPerCurl = 12;
  const double step = o.segment_mm / FibreStretch(o);
  return o.style == WigStyle::kCurly ? std::min(step, o.curl_pitch_mm / kPointsPerCurl) : step;
}

// What decides one grown strand: where it starts, which way it leaves the
// head and falls, and the random parts of its style.
struct StrandSeed {
  Eigen::Vector3d root, start_dir, fall_dir;
  double length_mm = 0;
  double lift_mm = 0;  // stiffness near the root: how far it follows start_dir
  double phase = 0, period_mm = 0;
  Eigen::Vector3d jitter = Eigen::Vector3d::Zero();
  WigStyle style = WigStyle::kStraight;
  int curl_handedness = 1;  // +1 right-handed, -1 left-handed
};

// Draws the random parts of a strand in a fixed order (the generator's
// output for a given seed depends on it).
void DrawStyle(const WigOptions& o, std::mt19937_64& rng, StrandSeed* s) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  s->length_mm = o.min_length_mm + (o.max_length_mm - o.min_length_mm) * uniform(rng);
  s->lift_mm = 12.0 + 10.0 * uniform(rng);
  s->phase = 2.0 * kPi * uniform(rng);
  s->period_mm = o.wave_period_mm * (0.85 + 0.3 * uniform(rng));
  s->jitter = 0.08 * Eigen::Vector3d(gauss(rng), gauss(rng), 0.0);
  // Drawn only when some curls wind left: a wig without any keeps its strands.
  if (o.curl_left_share > 0) s->curl_handedness = uniform(rng) < o.curl_left_share ? -1 : 1;
}

// Grows a strand's points from its seed: the centreline bends from start_dir
// to fall_dir, slides along the head instead of entering it, and carries the
// style's offset (waves, curls) that grows in over the first 30 mm.
std::vector<Eigen::Vector3f> Grow(const WigOptions& o, const HeadModel& head, const StrandSeed& s) {
  const double stretch = s.style == WigStyle::kCurly ? FibreStretch(o) : 1.0;
  WigOptions style_options = o;
  style_options.style = s.style;
  const double step = CentrelineStep(style_options);
  const int segments = std::max(2, static_cast<int>(std::ceil(s.length_mm / (step * stretch))));
  const double seg = s.length_mm / (segments * stretch);
  Eigen::Vector3d centre = s.root, previous = s.root, last_point = s.root;
  double fibre_mm = 0;
  std::vector<Eigen::Vector3f> points{s.root.cast<float>()};
  // The centreline advances by `seg` until the fibre has its length (the
  // curls' ramp near the root makes it need a few more steps than planned).
  for (int k = 1; fibre_mm < s.length_mm && k <= 4 * segments; ++k) {
    const double arc = k * seg;
    const double w = std::exp(-arc / s.lift_mm);
    Eigen::Vector3d tangent = (w * s.start_dir + (1.0 - w) * (s.fall_dir + s.jitter)).normalized();
    // Near the head, slide along it instead of stepping in: the strand keeps its length.
    Eigen::Vector3d surface_normal;
    head.SignedDistance(centre, &surface_normal);
    const double into_head = tangent.dot(surface_normal);
    if (into_head < 0 && head.IsNear(centre, 3.0))
      tangent = (tangent - into_head * surface_normal).normalized();
    centre = head.KeepOutside(centre + seg * tangent, 1.0);
    // A frame around the centreline for the style's offset; it grows from 0 at the root.
    tangent = (centre - previous).normalized();
    previous = centre;
    Eigen::Vector3d side = tangent.cross(s.start_dir);
    if (side.norm() < 1e-6) side = tangent.unitOrthogonal();
    side.normalize();
    const Eigen::Vector3d binormal = tangent.cross(side).normalized();
    const double ramp = std::min(1.0, arc / 30.0);
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    if (s.style == WigStyle::kWavy) {
      offset =
          ramp * o.wave_amplitude_mm * std::sin(2.0 * kPi * arc / s.period_mm + s.phase) * side;
    } else if (s.style == WigStyle::kCurly) {
      const double angle = 2.0 * kPi * arc / o.curl_pitch_mm + s.phase;
      offset = ramp * o.curl_radius_mm *
               (std::cos(angle) * side + s.curl_handedness * std::sin(angle) * binormal);
    }
    Eigen::Vector3d point = head.KeepOutside(centre + offset, 0.5);
    const double chord = (point - last_point).norm();
    if (fibre_mm + chord > s.length_mm && chord > 0) {
      // The tip: cut the last segment at the fibre's length, or end at the
      // previous point when only a sliver of it would remain.
      if (s.length_mm - fibre_mm < 0.2 * chord) break;
      point = last_point + (s.length_mm - fibre_mm) / chord * (point - last_point);
    }
    fibre_mm += (point - last_point).norm();
    last_point = point;
    points.push_back(point.cast<float>());
  }
  return points;
}

// The strands of a head without a scalp and without wisps: roots by direction
// from the ellipsoid's centre, each strand on its own.
StrandSet IndependentStrands(const WigOptions& o, const HeadModel& head) {
  std::mt19937_64 rng(o.seed);
  const HeadSpec& h = head.head();
  StrandSet set;
  for (int i = 0; i < o.num_strands; ++i) {
    StrandSeed s;
    s.style = o.style;
    const Eigen::Vector3d dir = SampleScalpDirection(o, rng);
    s.root = h.center_turntable_mm + dir.cwiseProduct(h.radii_mm);
    head.SignedDistance(s.root, &s.start_dir);
    s.fall_dir = Eigen::Vector3d(0, 0, -1);
    DrawStyle(o, rng, &s);
    set.AddStrand(Grow(o, head, s));
  }
  return set;
}

// The seed of a strand rooted at `root` (normal `normal`) on a head with a
// scalp: combed away from the parting; bangs fall forward over the forehead.
StrandSeed ScalpSeed(const WigOptions& o, const HeadModel& head, const Eigen::Vector3d& root,
                     const Eigen::Vector3d& normal, std::mt19937_64& rng) {
  StrandSeed s;
  s.style = o.style == WigStyle::kBangs ? WigStyle::kStraight : o.style;
  s.root = root;
  s.fall_dir = Eigen::Vector3d(0, 0, -1);
  DrawStyle(o, rng, &s);
  const ScalpSpec& scalp = head.head().scalp;
  const Eigen::Vector3d side_axis = Eigen::Vector3d::UnitZ().cross(scalp.face_dir);
  Eigen::Vector3d comb = Eigen::Vector3d::Zero();
  if (const int side = head.ScalpSide(root); side != 0) {
    const Eigen::Vector3d away = side * side_axis;
    comb = o.comb * (away - away.dot(normal) * normal);
  }
  s.start_dir = (normal + comb).normalized();
  double elevation, azimuth;
  head.ScalpAngles(root, &elevation, &azimuth);
  // Hair rooted towards the face is combed back and aside, not over the face.
  Eigen::Vector3d radial = root - scalp.center_turntable_mm;
  radial.z() = 0;
  if (azimuth < 110 && radial.norm() > 1e-9) {
    const double frontness = std::cos(DegToRad(std::min(90.0, azimuth)));
    s.fall_dir =
        (s.fall_dir + 0.25 * radial.normalized() - 0.45 * frontness * scalp.face_dir).normalized();
    s.start_dir = (s.start_dir - 1.2 * frontness * scalp.face_dir).normalized();
  }
  if (o.style == WigStyle::kBangs) {
    if (azimuth < 60 && elevation < scalp.hairline_front_deg + o.bangs_depth_deg) {
      // Forward and down over the forehead, cut short.
      s.start_dir = (normal + 0.8 * scalp.face_dir).normalized();
      s.fall_dir = (scalp.face_dir * 0.35 + Eigen::Vector3d(0, 0, -1)).normalized();
      s.length_mm =
          o.bangs_length_mm * (0.85 + 0.15 * s.length_mm / std::max(1.0, o.max_length_mm));
      s.lift_mm *= 1.6;
    }
  }
  return s;
}

// Rotation-minimising frames along a polyline (double reflection, Wang et al.
// 2008): per point a unit tangent t, and normals u, v with (t, u, v) right-handed.
struct Frames {
  std::vector<Eigen::Vector3d> t, u, v;
  std::vector<double> arc_mm;
};

Frames TransportFrames(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& first_u) {
  Frames f;
  const size_t n = points.size();
  f.t.resize(n), f.u.resize(n), f.v.resize(n), f.arc_mm.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const size_t a = i == 0 ? 0 : i - 1, b = i + 1 < n ? i + 1 : i;
    const Eigen::Vector3d d = (points[b] - points[a]).cast<double>();
    f.t[i] = d.norm() > 0 ? Eigen::Vector3d(d.normalized())
                          : (i > 0 ? f.t[i - 1] : Eigen::Vector3d::UnitZ());
    if (i > 0) f.arc_mm[i] = f.arc_mm[i - 1] + (points[i] - points[i - 1]).cast<double>().norm();
  }
  f.u[0] = (first_u - first_u.dot(f.t[0]) * f.t[0]);
  if (f.u[0].norm() < 1e-9) f.u[0] = f.t[0].unitOrthogonal();
  f.u[0].normalize();
  for (size_t i = 1; i < n; ++i) {
    const Eigen::Vector3d v1 = (points[i] - points[i - 1]).cast<double>();
    const double c1 = v1.squaredNorm();
    if (c1 < 1e-18) {
      f.u[i] = f.u[i - 1];
    } else {
      const Eigen::Vector3d r_l = f.u[i - 1] - (2 / c1) * v1.dot(f.u[i - 1]) * v1;
      const Eigen::Vector3d t_l = f.t[i - 1] - (2 / c1) * v1.dot(f.t[i - 1]) * v1;
      const Eigen::Vector3d v2 = f.t[i] - t_l;
      const double c2 = v2.squaredNorm();
      f.u[i] = c2 < 1e-18 ? r_l : Eigen::Vector3d(r_l - (2 / c2) * v2.dot(r_l) * v2);
      f.u[i] = (f.u[i] - f.u[i].dot(f.t[i]) * f.t[i]).normalized();
    }
  }
  for (size_t i = 0; i < n; ++i) f.v[i] = f.t[i].cross(f.u[i]);
  return f;
}

// A wisp's guide with its frames.
struct Wisp {
  std::vector<Eigen::Vector3f> points;
  Frames frames;
  Eigen::Vector3d root, root_normal;
};

// How much of a member's root offset remains at fraction s (0 root, 1 tip) of its length.
double ClumpScale(const WigOptions& o, double s) {
  const double smooth = s * s * (3 - 2 * s);
  if (o.clump_profile == ClumpProfile::kTip) return 1.0 - o.clump * smooth;
  return 1.0 - o.clump * std::sin(kPi * std::min(1.0, s));  // tightest half way, open at both ends
}

// A member strand of `wisp`, rooted at `root`: it follows the guide in the
// guide's own frames at its root's offset, clumped, frizzed, maybe a flyaway.
std::vector<Eigen::Vector3f> Member(const WigOptions& o, const HeadModel& head, const Wisp& wisp,
                                    const Eigen::Vector3d& root, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const Frames& f = wisp.frames;
  const Eigen::Vector3d offset0 = root - wisp.root;
  const double a_u = offset0.dot(f.u[0]), a_v = offset0.dot(f.v[0]), a_t = offset0.dot(f.t[0]);
  const double guide_length = f.arc_mm.back();
  const double length = guide_length * (0.82 + 0.18 * uniform(rng));
  // Frizz: two smooth random waves per axis, growing towards the tip.
  double frizz_phase[4], frizz_period[4];
  for (int k = 0; k < 4; ++k)
    frizz_phase[k] = 2 * kPi * uniform(rng), frizz_period[k] = 18 + 30 * uniform(rng);
  const bool flyaway = uniform(rng) < o.flyaway_fraction;
  const double fly_start = 0.2 + 0.5 * uniform(rng), fly_angle = 2 * kPi * uniform(rng);
  const double fly_reach = o.flyaway_mm * (0.5 + uniform(rng));
  std::vector<Eigen::Vector3f> points;
  points.reserve(wisp.points.size());
  for (size_t i = 0; i < wisp.points.size() && (i == 0 || f.arc_mm[i - 1] < length); ++i) {
    const double s = f.arc_mm[i] / std::max(1e-9, guide_length);
    const double scale = ClumpScale(o, s);
    double du = a_u * scale, dv = a_v * scale;
    const double frizz = o.frizz_mm * std::pow(s, 1.5);
    du += frizz * std::sin(2 * kPi * f.arc_mm[i] / frizz_period[0] + frizz_phase[0]) * 0.7 +
          frizz * 0.3 * std::sin(2 * kPi * f.arc_mm[i] / frizz_period[1] + frizz_phase[1]);
    dv += frizz * std::sin(2 * kPi * f.arc_mm[i] / frizz_period[2] + frizz_phase[2]) * 0.7 +
          frizz * 0.3 * std::sin(2 * kPi * f.arc_mm[i] / frizz_period[3] + frizz_phase[3]);
    if (flyaway && s > fly_start) {
      const double r = fly_reach * std::pow((s - fly_start) / (1 - fly_start), 2);
      du += r * std::cos(fly_angle), dv += r * std::sin(fly_angle);
    }
    Eigen::Vector3d p =
        wisp.points[i].cast<double>() + du * f.u[i] + dv * f.v[i] + (i == 0 ? a_t : 0.0) * f.t[i];
    if (i == 0) p = root;
    points.push_back(head.KeepOutside(p, 0.4).cast<float>());
  }
  // The tip at the member's length.
  if (points.size() >= 2) {
    double total = 0;
    for (size_t i = 1; i < points.size(); ++i) {
      const double seg = (points[i] - points[i - 1]).norm();
      if (total + seg > length) {
        const double keep = (length - total) / seg;
        points[i] = points[i - 1] + static_cast<float>(keep) * (points[i] - points[i - 1]);
        points.resize(keep < 0.2 ? i : i + 1);
        break;
      }
      total += seg;
    }
  }
  return points;
}

// Index of the wisp whose root is nearest to `p` (a coarse grid of roots).
class WispIndex {
 public:
  explicit WispIndex(const std::vector<Wisp>& wisps) : wisps_(wisps) {}
  size_t Nearest(const Eigen::Vector3d& p) const {
    size_t best = 0;
    double best_d = 1e300;
    for (size_t i = 0; i < wisps_.size(); ++i) {
      const double d = (wisps_[i].root - p).squaredNorm();
      if (d < best_d) best_d = d, best = i;
    }
    return best;
  }

 private:
  const std::vector<Wisp>& wisps_;
};

Wisp MakeWisp(std::vector<Eigen::Vector3f> points, const Eigen::Vector3d& normal) {
  Wisp w;
  w.root = points.front().cast<double>();
  w.root_normal = normal;
  w.points = std::move(points);
  w.frames = TransportFrames(w.points, normal);
  return w;
}

// Members around wisps: each root on the scalp joins the wisp whose root is
// nearest. Members are grown on up to 2 threads from per-strand seeds.
StrandSet Members(const WigOptions& o, const HeadModel& head, const std::vector<Wisp>& wisps) {
  std::vector<std::vector<Eigen::Vector3f>> strands(static_cast<size_t>(o.num_strands));
  const WispIndex index(wisps);
  ParallelFor(strands.size(), 2, [&] {
    return [&](size_t i) {
      std::mt19937_64 rng(o.seed * 0x9E3779B97F4A7C15ull + 1000003ull * (i + 1));
      Eigen::Vector3d normal;
      const Eigen::Vector3d root = head.SampleScalp(rng, &normal);
      strands[i] = Member(o, head, wisps[index.Nearest(root)], root, rng);
    };
  });
  StrandSet set;
  for (const auto& s : strands) set.AddStrand(s);
  return set;
}

Result<StrandSet> FileGuidedWig(const WigOptions& o, const HeadModel& head) {
  auto guides = ReadStrands(o.file);
  if (!guides.ok()) return guides.status().WithContext("wig.file");
  for (auto& p : guides->points_mm) p = (o.turntable_from_file * p.cast<double>()).cast<float>();
  if (static_cast<size_t>(o.num_strands) <= guides->num_strands()) return guides;
  std::vector<Wisp> wisps;
  const auto offsets = guides->Offsets();
  for (size_t s = 0; s < guides->num_strands(); ++s) {
    if (offsets[s + 1] - offsets[s] < 2) continue;
    std::vector<Eigen::Vector3f> points(
        guides->points_mm.begin() + static_cast<std::ptrdiff_t>(offsets[s]),
        guides->points_mm.begin() + static_cast<std::ptrdiff_t>(offsets[s + 1]));
    Eigen::Vector3d normal;
    head.SignedDistance(points.front().cast<double>(), &normal);
    wisps.push_back(MakeWisp(std::move(points), normal));
  }
  if (wisps.empty())
    return InvalidArgument("wig.file " + o.file +
                           ": no strand with two or more points to guide wisps");
  return Members(o, head, wisps);
}

}  // namespace

Result<StrandSet> GenerateWig(const WigOptions& o, const HeadModel& head) {
  HR_RETURN_IF_ERROR(o.Check());
  if (o.style == WigStyle::kFile) return FileGuidedWig(o, head);
  if (!head.head().scalp.defined && o.wisps == 0) return IndependentStrands(o, head);
  if (!head.head().scalp.defined) {
    return InvalidArgument("wig.wisps needs head.scalp: the region wisps are rooted in");
  }
  std::mt19937_64 rng(o.seed);
  const int guides = o.wisps > 0 ? o.wisps : o.num_strands;
  std::vector<Wisp> wisps;
  wisps.reserve(static_cast<size_t>(guides));
  for (int i = 0; i < guides; ++i) {
    Eigen::Vector3d normal;
    const Eigen::Vector3d root = head.SampleScalp(rng, &normal);
    wisps.push_back(MakeWisp(Grow(o, head, ScalpSeed(o, head, root, normal, rng)), normal));
  }
  if (o.wisps == 0) {
    StrandSet set;
    for (const Wisp& w : wisps) set.AddStrand(w.points);
    return set;
  }
  return Members(o, head, wisps);
}

Result<StrandSet> GenerateWig(const WigOptions& options, const HeadSpec& head) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(std::unique_ptr<HeadModel> model, HeadModel::Build(head));
  return GenerateWig(options, *model);
}

}  // namespace hairrig
