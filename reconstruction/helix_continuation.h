// A strand's curl carried on where no seen strand guides it.
//
// Where a grown strand follows seen strands (strand_growth.h's follow term),
// its tangents turn as the hair curls. Past them, in the hair's unseen inside,
// Bao & Qi's field (Sec. IV-A, Eq. 1) is a smooth Laplace interpolation: a
// strand grown along it runs straight down the curls' axis, where every true
// tangent of a ringlet lies its helix angle (about 60 deg on tight curls) off.
// HelixContinuation keeps the last window of tangents the strand followed,
// fits the Darboux vector Omega of that stretch (dT/ds = Omega x T, constant on
// a helix; least squares over the window), and past the seen strands turns
// the tangent about the field's direction at the rate |Omega|, in Omega's
// sense, at the window's mean angle to Omega's axis: a helix whose axis
// follows the field, as Bao & Qi fit strands with piecewise helices (Sec. V).
// A window whose Omega lies nearly across the strand (a wave in one plane)
// keeps the tangents' spread about their mean instead: it wiggles about the
// field rather than circling it. The helix's radius is held to twice what the
// window strays from its mean direction.
//
// Units: mm and radians; tangents unit vectors in the points' frame.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hairrig {

struct HelixContinuationOptions {
  double window_mm = 16;  // the seen stretch the curl is measured over
  // Below this mean curvature (rad/mm) over the window the strand is taken as
  // straight and nothing is carried on (curly_blond's segments bend at a
  // median 0.061 /mm, its true strands at 0.158; docs/accuracy.md).
  double min_curvature_per_mm = 0.04;
  double max_rate_per_mm = 0.5;  // |Omega| is clamped to this (curls of radius >= 2 mm)
};

class HelixContinuation {
 public:
  HelixContinuation(const HelixContinuationOptions& options, double step_mm);

  // A tangent the strand took while following a seen strand.
  void Follow(const Eigen::Vector3f& tangent);

  // The bend of the last `span` steps followed, at their middle: the unit
  // tangent (the mean of the first and last tangents) and principal normal
  // (towards the side they turn to). False when the window holds fewer
  // steps, or they turn by less than `min_turn` (rad) in all. The caller
  // knows whether they were followed in one run.
  bool Bend(size_t span, double min_turn, Eigen::Vector3f* tangent, Eigen::Vector3f* normal) const;

  // The next tangent past the seen strands: `previous` turned about `axis`
  // (unit, the field's direction) as the window's helix turns. False, and
  // *next untouched, when the window is not full or the strand is straight.
  bool Continue(const Eigen::Vector3f& previous, const Eigen::Vector3f& axis,
                Eigen::Vector3f* next);

 private:
  // Fits the window's helix (rate_, helix_angle_, handedness_); false when straight.
  bool Fit();

  HelixContinuationOptions options_;
  double step_mm_;
  size_t window_steps_;
  std::vector<Eigen::Vector3f> window_;  // ring buffer of the last tangents followed
  size_t next_slot_ = 0;
  bool filled_ = false;
  bool fitted_ = false;     // the fit below is of the current window
  bool continued_ = false;  // Continue has turned the strand since the last Follow
  bool curly_ = false;
  double rate_ = 0;         // |Omega|, rad/mm
  double helix_angle_ = 0;  // between the tangents and Omega's axis, rad
  float handedness_ = 1;    // +1: Omega points along the strand's way, -1 against it
};

}  // namespace hairrig
