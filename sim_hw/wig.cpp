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
  StrandSet set;
  set.points_mm.reserve(static_cast<size_t>(o.num_strands) *
                        static_cast<size_t>(o.max_length_mm / o.segment_mm + 2));
  std::vector<Eigen::Vector3f> points;
  for (int s = 0; s < o.num_strands; ++s) {
    const Eigen::Vector3d dir = SampleScalpDirection(o, rng);
    const Eigen::Vector3d root = head.center_turntable_mm + dir.cwiseProduct(head.radii_mm);
    const Eigen::Vector3d normal = EllipsoidNormal(root, head);
    const double length = o.min_length_mm + (o.max_length_mm - o.min_length_mm) * uniform(rng);
    const int segments = std::max(2, static_cast<int>(std::ceil(length / o.segment_mm)));
    const double seg = length / segments;
    // Stiffness of the first part of the strand: how far it follows the normal.
    const double lift_mm = 12.0 + 10.0 * uniform(rng);
    const double phase = 2.0 * kPi * uniform(rng);
    const double period = o.wave_period_mm * (0.85 + 0.3 * uniform(rng));
    const Eigen::Vector3d jitter = 0.08 * Eigen::Vector3d(gauss(rng), gauss(rng), 0.0);
    Eigen::Vector3d centre = root;
    Eigen::Vector3d previous = root;
    points.clear();
    points.push_back(root.cast<float>());
    for (int k = 1; k <= segments; ++k) {
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
      points.push_back(KeepOutside(centre + offset, head, 0.5).cast<float>());
    }
    set.AddStrand(points);
  }
  return set;
}

}  // namespace hairrig
