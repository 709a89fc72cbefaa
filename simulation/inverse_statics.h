// Inverse statics (Bao & Qi 2017, Sec. VI, after Derouet-Jourdan et al., ref.
// [39]): the fitted shape q is made a static equilibrium, so that a fitted
// hairstyle does not sag when the simulation starts. With q' = 0 the
// equations of motion reduce to K (q - q^0) = Q(q), the generalised forces of
// gravity, the frame's motion and the contact at rest; the rest curvatures
// q^0 = q - K^-1 Q(q) solve it exactly.
//
// Decision: the paper keeps q^0 = q and looks for contact forces instead; that
// holds only where the hair rests on the head. Free-hanging strands (bangs,
// long hair below the head) have no contact to lean on, so we change q^0 for
// the whole strand and keep the penalty contact forces that already act on it.
#pragma once

#include <Eigen/Core>

#include "core/status.h"
#include "simulation/super_helix_dynamics.h"

namespace hairrig {

struct InverseStaticsReport {
  double max_rest_change = 0;  // |q^0 - q| max over coordinates, rad/m
  double residual_force = 0;   // |K (q - q^0) - Q| after the solve, relative to |Q|
};

// Sets dynamics->strand().rest_q. InvalidArgument if q has the wrong size or
// is not finite.
Status SolveInverseStatics(const Environment& environment, const Eigen::VectorXd& q,
                           SuperHelixDynamics* dynamics, InverseStaticsReport* report = nullptr);

}  // namespace hairrig
