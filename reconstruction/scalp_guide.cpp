#include "reconstruction/scalp_guide.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/transform.h"

namespace hairrig {

namespace {

constexpr double kGridCellMm = 16;
constexpr int kRootTries = 8;

Eigen::Vector3f SafeNormalized(const Eigen::Vector3f& v, const Eigen::Vector3f& fallback) {
  const float norm = v.norm();
  return norm > 1e-6f ? Eigen::Vector3f(v / norm) : fallback;
}

// The unit vector a fraction s of the way from a to b along their great circle.
Eigen::Vector3f Slerp(const Eigen::Vector3f& a, const Eigen::Vector3f& b, double angle_rad,
                      double s) {
  if (angle_rad < 1e-6) return b;
  const double sin_angle = std::sin(angle_rad);
  const Eigen::Vector3f v = static_cast<float>(std::sin((1 - s) * angle_rad) / sin_angle) * a +
                            static_cast<float>(std::sin(s * angle_rad) / sin_angle) * b;
  return v.normalized();
}

// Distance between two angles on the circle (rad, in [0, pi]).
double AngleBetween(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 2 * kPi);
  return std::min(d, 2 * kPi - d);
}

}  // namespace

ScalpGuide::ScalpGuide(const HeadModel& head, const Eigen::Vector3f& down) : head_(head) {
  const ScalpSpec& scalp = head.head().scalp;
  const Eigen::Vector3d bounds_centre = 0.5 * (head.mesh().MinCorner() + head.mesh().MaxCorner());
  centre_ = (scalp.defined ? head.ScalpCenter() : bounds_centre).cast<float>();
  up_ = SafeNormalized(-down, Eigen::Vector3f::UnitZ());
  const Eigen::Vector3f face = scalp.face_dir.cast<float>();
  face_ = SafeNormalized(face - face.dot(up_) * up_, up_.unitOrthogonal());
  has_parting_ = scalp.defined && scalp.parting;
  const Eigen::Vector3f side = up_.cross(face_);
  parting_normal_ =
      Eigen::AngleAxisf(static_cast<float>(DegToRad(scalp.parting_offset_deg)), face_) * side;
  parting_up_ = face_.cross(parting_normal_);
  parting_begin_rad_ = DegToRad(scalp.hairline_front_deg);
  parting_end_rad_ = DegToRad(90 + scalp.parting_back_deg);
  for (const Eigen::Vector3d& v : head.mesh().vertices_mm) {
    if (head.OnScalp(v)) samples_.push_back(v.cast<float>());
  }
  grid_ = std::make_unique<PointGrid>(samples_, kGridCellMm);
}

Eigen::Vector3f ScalpGuide::NearestSample(const Eigen::Vector3f& q) const {
  const int64_t near = grid_->Nearest(q, 2 * kGridCellMm);
  if (near >= 0) return samples_[static_cast<size_t>(near)];
  size_t best = 0;
  float best2 = std::numeric_limits<float>::max();
  for (size_t i = 0; i < samples_.size(); ++i) {
    const float d2 = (samples_[i] - q).squaredNorm();
    if (d2 < best2) best2 = d2, best = i;
  }
  return samples_.empty() ? q : samples_[best];
}

bool ScalpGuide::AnySampleWithin(const Eigen::Vector3f& q, double distance_mm) const {
  return grid_->Nearest(q, distance_mm) >= 0;
}

Eigen::Vector3f ScalpGuide::SurfaceAlong(const Eigen::Vector3f& direction,
                                         double fallback_radius_mm) const {
  HeadHit hit;
  if (head_.Intersect(centre_.cast<double>(), direction.cast<double>(), 1e-6, 1e5, &hit)) {
    return centre_ + static_cast<float>(hit.t) * direction;
  }
  return centre_ + static_cast<float>(fallback_radius_mm) * direction;
}

Eigen::Vector3f ScalpGuide::OntoSurface(const Eigen::Vector3f& p) const {
  Eigen::Vector3d q = p.cast<double>();
  for (int iteration = 0; iteration < 3; ++iteration) {
    Eigen::Vector3d outward;
    const double d = head_.SignedDistance(q, &outward);
    q -= d * outward;
  }
  return q.cast<float>();
}

Eigen::Vector3f ScalpGuide::Outward(const Eigen::Vector3f& p) const {
  Eigen::Vector3d outward;
  head_.SignedDistance(p.cast<double>(), &outward);
  return outward.cast<float>();
}

Eigen::Vector3f ScalpGuide::PartingDirection(const Eigen::Vector3f& from_centre) const {
  if (!has_parting_) return up_;
  double angle = std::atan2(from_centre.dot(parting_up_), from_centre.dot(face_));
  if (angle < parting_begin_rad_ || angle > parting_end_rad_) {
    angle = AngleBetween(angle, parting_begin_rad_) < AngleBetween(angle, parting_end_rad_)
                ? parting_begin_rad_
                : parting_end_rad_;
  }
  return static_cast<float>(std::cos(angle)) * face_ +
         static_cast<float>(std::sin(angle)) * parting_up_;
}

Eigen::Vector3f ScalpGuide::ReferenceDirection(const Eigen::Vector3f& p) const {
  const Eigen::Vector3f u = SafeNormalized(p - centre_, up_);
  const Eigen::Vector3f a = PartingDirection(u);
  // On the parting (or at the crown) the arc has no direction: away from the
  // parting's plane, or to the back of the head.
  const Eigen::Vector3f degenerate =
      has_parting_
          ? Eigen::Vector3f(u.dot(parting_normal_) >= 0 ? parting_normal_ : -parting_normal_)
          : Eigen::Vector3f(-face_);
  const Eigen::Vector3f along_arc = SafeNormalized(a.dot(u) * u - a, degenerate);
  const Eigen::Vector3f n = Outward(p);
  return SafeNormalized(along_arc - along_arc.dot(n) * n, along_arc);
}

std::vector<Eigen::Vector3f> ScalpGuide::PathFromParting(const Eigen::Vector3f& p,
                                                         double step_mm) const {
  const float radius = (p - centre_).norm();
  const Eigen::Vector3f u = SafeNormalized(p - centre_, up_);
  const Eigen::Vector3f a = PartingDirection(u);
  const double angle = std::acos(std::clamp(static_cast<double>(a.dot(u)), -1.0, 1.0));
  const int steps = std::max(1, static_cast<int>(std::ceil(angle * radius / step_mm)));
  std::vector<Eigen::Vector3f> path;
  path.reserve(static_cast<size_t>(steps) + 1);
  for (int k = 0; k < steps; ++k) {
    path.push_back(SurfaceAlong(Slerp(a, u, angle, static_cast<double>(k) / steps), radius));
  }
  path.push_back(p);
  return path;
}

Eigen::Vector3f ScalpGuide::GrowingDirection(const Eigen::Vector3f& r,
                                             const Eigen::Vector3f& q) const {
  const Eigen::Vector3f n = Outward(r);
  const Eigen::Vector3f reference = ReferenceDirection(r);
  const Eigen::Vector3f towards_q = SafeNormalized(q - r, reference);
  return n.dot(reference) > n.dot(towards_q) ? reference : towards_q;
}

ScalpRoot ScalpGuide::AssignRoot(const Eigen::Vector3f& q, double step_mm, double jitter_mm,
                                 std::mt19937_64& rng) const {
  const Eigen::Vector3f p = NearestSample(q);
  const std::vector<Eigen::Vector3f> path = PathFromParting(p, step_mm);
  size_t most_compatible = path.size() - 1;  // p_M of Eq. 11
  float best = -std::numeric_limits<float>::max();
  for (size_t i = 0; i < path.size(); ++i) {
    const Eigen::Vector3f to_q = q - path[i];
    if (to_q.norm() < 1e-6f) continue;
    const float compatibility = to_q.normalized().dot(ReferenceDirection(path[i]));
    if (compatibility > best) best = compatibility, most_compatible = i;
  }
  const size_t k = std::uniform_int_distribution<size_t>(0, most_compatible)(rng);
  const auto on_scalp = [&](const Eigen::Vector3f& x) { return head_.OnScalp(x.cast<double>()); };
  ScalpRoot root;
  root.position = p;
  bool found = false;
  const Eigen::Vector3f n_k = Outward(path[k]);
  std::normal_distribution<float> gaussian;
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (int attempt = 0; attempt < kRootTries && !found; ++attempt) {
    Eigen::Vector3f g(gaussian(rng), gaussian(rng), gaussian(rng));
    g = SafeNormalized(g - g.dot(n_k) * n_k, n_k.unitOrthogonal());
    const Eigen::Vector3f moved =
        path[k] + static_cast<float>(jitter_mm) * std::sqrt(uniform(rng)) * g;
    const Eigen::Vector3f candidate =
        SurfaceAlong(SafeNormalized(moved - centre_, up_), (moved - centre_).norm());
    if (on_scalp(candidate)) root.position = candidate, found = true;
  }
  for (size_t i = k; i < path.size() && !found; ++i) {
    if (on_scalp(path[i])) root.position = path[i], found = true;
  }
  root.normal = Outward(root.position);
  root.growing_direction = GrowingDirection(root.position, q);
  return root;
}

}  // namespace hairrig
