#include "simulation/inverse_statics.h"

#include <string>

namespace hairrig {

Status SolveInverseStatics(const Environment& environment, const Eigen::VectorXd& q,
                           SuperHelixDynamics* dynamics, InverseStaticsReport* report) {
  if (q.size() != dynamics->strand().num_dofs() || !q.allFinite()) {
    return InvalidArgument("inverse statics: the coordinates must be " +
                           std::to_string(dynamics->strand().num_dofs()) + " finite values");
  }
  const Eigen::VectorXd forces = dynamics->StaticForces(environment, q);
  const Eigen::VectorXd& stiffness = dynamics->StiffnessDiagonal();
  Eigen::VectorXd& rest = dynamics->mutable_strand().rest_q;
  rest = q - forces.cwiseQuotient(stiffness);
  if (report) {
    report->max_rest_change = (rest - q).cwiseAbs().maxCoeff();
    const Eigen::VectorXd residual = dynamics->ElasticForces(q) + forces;
    report->residual_force = residual.norm() / std::max(forces.norm(), 1e-300);
  }
  return Status::Ok();
}

}  // namespace hairrig
