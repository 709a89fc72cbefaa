#include "reconstruction/helix_continuation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace hairrig {

HelixContinuation::HelixContinuation(const HelixContinuationOptions& options, double step_mm)
    : options_(options),
      step_mm_(step_mm),
      window_steps_(static_cast<size_t>(std::max(3.0, std::round(options.window_mm / step_mm)))) {
  window_.reserve(window_steps_);
}

void HelixContinuation::Follow(const Eigen::Vector3f& tangent) {
  if (continued_) {  // a window across an unseen stretch would mix two curls
    window_.clear();
    next_slot_ = 0;
    filled_ = false;
    continued_ = false;
  }
  if (window_.size() < window_steps_) {
    window_.push_back(tangent);
  } else {
    window_[next_slot_] = tangent;
  }
  next_slot_ = (next_slot_ + 1) % window_steps_;
  filled_ = window_.size() == window_steps_;
  fitted_ = false;
}

bool HelixContinuation::Bend(size_t span, double min_turn, Eigen::Vector3f* tangent,
                             Eigen::Vector3f* normal) const {
  if (span < 1 || window_.size() <= span) return false;
  const size_t n = window_.size();
  const Eigen::Vector3f& last = window_[(next_slot_ + n - 1) % n];
  const Eigen::Vector3f& first = window_[(next_slot_ + n - 1 - span) % n];
  // For unit tangents the sum and the difference are square to each other.
  const Eigen::Vector3f turn = last - first;
  if (!(turn.norm() >= 2 * std::sin(0.5 * min_turn))) return false;
  *tangent = (last + first).normalized();
  *normal = turn.normalized();
  return true;
}

namespace {

// The angle between a window's tangents `t` and its helix's axis: their mean
// angle to Omega's axis, unless Omega lies nearly across the strand (within
// 15 deg of square to the `mean` tangent), as for a wave in one plane, whose
// Omega flips from bend to bend: then the spread of the tangents about their
// mean, so that such a strand turns gently about the field instead of
// circling it.
double HelixAngle(const std::vector<Eigen::Vector3d>& t, const Eigen::Vector3d& omega,
                  const Eigen::Vector3d& mean) {
  const double across = std::cos(75 * M_PI / 180);
  const Eigen::Vector3d axis = omega.normalized() * (omega.dot(mean) >= 0 ? 1.0 : -1.0);
  if (axis.dot(mean.normalized()) < across) return std::acos(std::clamp(mean.norm(), 0.0, 1.0));
  double to_axis = 0;
  for (size_t k = 0; k + 1 < t.size(); ++k)
    to_axis += std::acos(std::clamp(t[k].dot(axis), -1.0, 1.0));
  return std::min(to_axis / static_cast<double>(t.size() - 1), M_PI / 2);
}

// How far a path with tangents `t` (steps of step_mm) strays from the line
// through its start along `direction` (unit), at most.
double Straying(const std::vector<Eigen::Vector3d>& t, const Eigen::Vector3d& direction,
                double step_mm) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double most = 0;
  for (const Eigen::Vector3d& tk : t) {
    p += tk * step_mm;
    most = std::max(most, (p - p.dot(direction) * direction).norm());
  }
  return most;
}

}  // namespace

bool HelixContinuation::Fit() {
  // Oldest first: the ring starts at the next slot to be written.
  std::vector<Eigen::Vector3d> t(window_steps_);
  for (size_t k = 0; k < window_steps_; ++k)
    t[k] = window_[(next_slot_ + k) % window_steps_].cast<double>().normalized();
  // Least squares for dT/ds = Omega x T over the window's steps:
  // sum (I - T T^T) Omega = sum T x dT/ds.
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity() * 1e-9;
  Eigen::Vector3d b = Eigen::Vector3d::Zero(), mean = Eigen::Vector3d::Zero();
  double curvature = 0;
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    const Eigen::Vector3d d = (t[k + 1] - t[k]) / step_mm_;
    a += Eigen::Matrix3d::Identity() - t[k] * t[k].transpose();
    b += t[k].cross(d);
    curvature += d.norm();
    mean += t[k];
  }
  curvature /= static_cast<double>(t.size() - 1);
  const Eigen::Vector3d omega = a.ldlt().solve(b);
  if (curvature < options_.min_curvature_per_mm || !omega.allFinite() || omega.norm() < 1e-9)
    return false;
  handedness_ = omega.dot(mean) >= 0 ? 1.0f : -1.0f;
  rate_ = std::min(omega.norm(), options_.max_rate_per_mm);
  // The helix's radius sin(angle) / rate at most twice what the seen window
  // strays from its mean direction (under a turn strays less than the curl's
  // diameter): a loose fit does not loop wider than the hair curled.
  const double straying = Straying(t, mean.normalized(), step_mm_);
  helix_angle_ = std::min(HelixAngle(t, omega, mean / static_cast<double>(t.size() - 1)),
                          std::asin(std::min(1.0, 2 * rate_ * straying)));
  return true;
}

bool HelixContinuation::Continue(const Eigen::Vector3f& previous, const Eigen::Vector3f& axis,
                                 Eigen::Vector3f* next) {
  if (!filled_) return false;
  if (!fitted_) {
    curly_ = Fit();
    fitted_ = true;
  }
  if (!curly_) return false;
  const Eigen::Vector3d a = axis.cast<double>().normalized();
  Eigen::Vector3d across = previous.cast<double>() - previous.cast<double>().dot(a) * a;
  if (across.norm() < 1e-3) across = a.unitOrthogonal();
  across.normalize();
  // Turn about the axis by one step of the helix (dT/ds = Omega x T, Omega along the axis).
  const double turn = handedness_ * rate_ * step_mm_;
  across = std::cos(turn) * across + std::sin(turn) * a.cross(across);
  *next = (std::cos(helix_angle_) * a + std::sin(helix_angle_) * across).normalized().cast<float>();
  continued_ = true;
  return true;
}

}  // namespace hairrig
