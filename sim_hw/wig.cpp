#include "sim_hw/wig.h"

#include <cmath>
#include <random>

#include "core/strand_io.h"
#include "core/transform.h"

namespace hairrig {
namespace {

// Pushes `p` out of the head ellipsoid (scaled by `margin`) along the normal.
Eigen::Vector3d KeepOutside(const Eigen::Vector3d& p, const SceneHead& head, double margin_mm) {
  const Eigen::Vector3d r = head.radii_mm.array() + margin_mm;
  const Eigen::Vector3d q = (p - head.center_turntable_mm).cwiseQuotient(r);
  const double n = q.norm();
  if (n >= 1.0 || n < 1e-9) return p;
  return head.center_turntable_mm + (q / n).cwiseProduct(r);
}

// True within `margin_mm` (roughly) of the head's surface or inside it.
bool IsNearHead(const Eigen::Vector3d& p, const SceneHead& head, double margin_mm) {
  const Eigen::Vector3d r = head.radii_mm.array() + margin_mm;
  return (p - head.center_turntable_mm).cwiseQuotient(r).norm() < 1.0;
}

Eigen::Vector3d EllipsoidNormal(const Eigen::Vector3d& p, const SceneHead& head) {
  const Eigen::Vector3d r2 = head.radii_mm.cwiseProduct(head.radii_mm);
  return (p - head.center_turntable_mm).cwiseQuotient(r2).normalized();
}

// A root direction (unit, from the head centre) on the scalp region.
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

}  // namespace

Result<StrandSet> GenerateWig(const WigOptions& o, const SceneHead& head) {
  if (o.style == WigStyle::kFile) {
    auto strands = ReadStrands(o.file);
    if (!strands.ok()) return strands.status().WithContext("wig.file");
    return strands;
  }
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Vector3d down(0, 0, -1);
  const double stretch = FibreStretch(o), step = CentrelineStep(o);
  StrandSet set;
  set.points_mm.reserve(static_cast<size_t>(o.num_strands) *
                        static_cast<size_t>(o.max_length_mm / (step * stretch) + 2));
  std::vector<Eigen::Vector3f> points;
  for (int s = 0; s < o.num_strands; ++s) {
    const Eigen::Vector3d dir = SampleScalpDirection(o, rng);
    const Eigen::Vector3d root = head.center_turntable_mm + dir.cwiseProduct(head.radii_mm);
    const Eigen::Vector3d normal = EllipsoidNormal(root, head);
    // The fibre's length (along the strand, curls included).
    const double length = o.min_length_mm + (o.max_length_mm - o.min_length_mm) * uniform(rng);
    const int segments = std::max(2, static_cast<int>(std::ceil(length / (step * stretch))));
    const double seg = length / (segments * stretch);
    // Stiffness of the first part of the strand: how far it follows the normal.
    const double lift_mm = 12.0 + 10.0 * uniform(rng);
    const double phase = 2.0 * kPi * uniform(rng);
    const double period = o.wave_period_mm * (0.85 + 0.3 * uniform(rng));
    const Eigen::Vector3d jitter = 0.08 * Eigen::Vector3d(gauss(rng), gauss(rng), 0.0);
    Eigen::Vector3d centre = root;
    Eigen::Vector3d previous = root;
    Eigen::Vector3d last_point = root;
    double fibre_mm = 0;
    points.clear();
    points.push_back(root.cast<float>());
    // The centreline advances by `seg` until the fibre has its length (the
    // curls' ramp near the root makes it need a few more steps than planned).
    for (int k = 1; fibre_mm < length && k <= 4 * segments; ++k) {
      const double arc = k * seg;
      const double w = std::exp(-arc / lift_mm);
      Eigen::Vector3d tangent = (w * normal + (1.0 - w) * (down + jitter)).normalized();
      // Near the head, slide along it instead of stepping in: the strand keeps its length.
      const Eigen::Vector3d surface_normal = EllipsoidNormal(centre, head);
      const double into_head = tangent.dot(surface_normal);
      if (into_head < 0 && IsNearHead(centre, head, 3.0)) {
        tangent = (tangent - into_head * surface_normal).normalized();
      }
      centre = KeepOutside(centre + seg * tangent, head, 1.0);
      // A frame around the centreline for the style's offset; it grows from 0 at the root.
      tangent = (centre - previous).normalized();
      previous = centre;
      Eigen::Vector3d side = tangent.cross(normal);
      if (side.norm() < 1e-6) side = tangent.unitOrthogonal();
      side.normalize();
      const Eigen::Vector3d binormal = tangent.cross(side).normalized();
      const double ramp = std::min(1.0, arc / 30.0);
      Eigen::Vector3d offset = Eigen::Vector3d::Zero();
      if (o.style == WigStyle::kWavy) {
        offset = ramp * o.wave_amplitude_mm * std::sin(2.0 * kPi * arc / period + phase) * side;
      } else if (o.style == WigStyle::kCurly) {
        const double angle = 2.0 * kPi * arc / o.curl_pitch_mm + phase;
        offset = ramp * o.curl_radius_mm * (std::cos(angle) * side + std::sin(angle) * binormal);
      }
      Eigen::Vector3d point = KeepOutside(centre + offset, head, 0.5);
      const double chord = (point - last_point).norm();
      if (fibre_mm + chord > length && chord > 0) {
        // The tip: cut the last segment at the fibre's length, or end at the
        // previous point when only a sliver of it would remain.
        if (length - fibre_mm < 0.2 * chord) break;
        point = last_point + (length - fibre_mm) / chord * (point - last_point);
      }
      fibre_mm += (point - last_point).norm();
      last_point = point;
      points.push_back(point.cast<float>());
    }
    set.AddStrand(points);
  }
  return set;
}

}  // namespace hairrig
