// Guide-to-full interpolation (Bao & Qi 2017, end of Sec. VI, after Chai et
// al., ref. [40]): every particle of every strand of the full model moves with
// a few particles of nearby guides, with weights from a linearly constrained
// least-squares fit at rest. Millimetres, world frame.
//
// For particle p at arc length s (mm from the root) on its strand, the
// candidates are the particles g_k on the K guides whose roots are nearest
// the strand's root, at the same arc length s on a guide at least as long as
// the strand and at the same share of the length on a shorter one. The paper
// does not say which guide particles are used; matched by the share of the
// length everywhere, a strand much shorter than its guides (a
// reconstruction's short strands at a parting) would move with the guides'
// tips and stretch many times over. Its weights minimise
//   |sum_k w_k g_k - p|^2 + beta sum_k d_k^2 w_k^2   subject to  sum_k w_k = 1
// (d_k: distance from p to g_k at rest; the second term keeps the weights with
// the near guides where the fit alone is ambiguous), solved in
// closed form from its KKT system. The particle then follows the guides'
// displacements: p(t) = p_rest + sum_k w_k (g_k(t) - g_k(rest)), so the rest
// shape is reproduced exactly (ours: ref. [40] interpolates positions).
// Blending guides that move apart lengthens a strand; with keep_lengths each
// strand is then rebuilt from its root, every segment keeping its blended
// direction and its rest length (ours; off, the plain blend).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

struct GuideInterpolationOptions {
  int guides_per_strand = 4;    // K
  double regularisation = 0.1;  // beta
  bool keep_lengths = true;     // restore each segment's rest length after the blend

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

class GuideInterpolation {
 public:
  // `full_rest` are the strands to drive; `guides_rest` the guides' curves at
  // rest (root first, any number of points each). InvalidArgument for no
  // guide, a guide of fewer than 2 points, non-finite input or bad options.
  static Result<GuideInterpolation> Build(
      const StrandSet& full_rest, const std::vector<std::vector<Eigen::Vector3d>>& guides_rest,
      const GuideInterpolationOptions& options);

  // The full strands for the guides' curves now (same guides, same point
  // counts as at rest). InvalidArgument if the counts differ.
  Result<StrandSet> Apply(const std::vector<std::vector<Eigen::Vector3d>>& guides_now) const;

  // RMS over particles of |sum_k w_k g_k(rest) - p_rest|, mm: how well the
  // guides' rest shape explains each particle (0 is a perfect fit).
  double rest_fit_rms_mm() const { return rest_fit_rms_mm_; }

 private:
  struct Particle {
    int guides[8];
    double weights[8];
    int segment[8];   // the particle's place on each guide: between points
    double blend[8];  // segment - 1 and segment, this far along
  };
  StrandSet rest_;
  std::vector<std::vector<Eigen::Vector3d>> guides_rest_;
  std::vector<Particle> particles_;  // one per point of rest_
  bool keep_lengths_ = true;
  int per_particle_ = 0;
  double rest_fit_rms_mm_ = 0;
};

}  // namespace hairrig
