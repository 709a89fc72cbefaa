#include "simulation/super_helix_dynamics.h"

#include <cmath>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "simulation/helix.h"

namespace hairrig {

namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Gauss-Legendre nodes on [0, 1] and weights summing to 1.
void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  static const double kNodes[5][5] = {{0},
                                      {-0.5773502691896257, 0.5773502691896257},
                                      {-0.7745966692414834, 0, 0.7745966692414834},
                                      {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526},
                                      {-0.9061798459386640, -0.5384693101056831, 0, 0.5384693101056831,
                                       0.9061798459386640}};
  static const double kWeights[5][5] = {{2},
                                        {1, 1},
                                        {0.5555555555555556, 0.8888888888888888, 0.5555555555555556},
                                        {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538},
                                        {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                         0.2369268850561891}};
  nodes->clear();
  weights->clear();
  for (int i = 0; i < n; ++i) {
    nodes->push_back(0.5 * (kNodes[n - 1][i] + 1));
    weights->push_back(0.5 * kWeights[n - 1][i]);
  }
}

// d HelixOffset(e_1, omega, s) / d omega (3 x 3) by central differences: the
// closed form is smooth in omega, and the step keeps both the truncation and
// the rounding error near 1e-10 relative.
Eigen::Matrix3d OffsetJacobian(const Eigen::Vector3d& omega, double s, double length) {
  const double h = 1e-6 * (omega.norm() + 1 / length);
  Eigen::Matrix3d d;
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d plus = omega;
    Eigen::Vector3d minus = omega;
    plus[j] += h;
    minus[j] -= h;
    d.col(j) = (HelixOffset(Eigen::Vector3d::UnitX(), plus, s) - HelixOffset(Eigen::Vector3d::UnitX(), minus, s)) /
               (2 * h);
  }
  return d;
}

}  // namespace

double HeadEllipsoid::Distance(const Eigen::Vector3d& p, Eigen::Vector3d* normal) const {
  const Eigen::Vector3d u = (p - center_m).cwiseQuotient(radii_m);
  const double g = u.norm();
  if (g < 1e-12) {
    *normal = Eigen::Vector3d::UnitZ();
    return -radii_m.minCoeff();
  }
  const Eigen::Vector3d gradient = u.cwiseQuotient(radii_m) / g;
  const double gradient_norm = gradient.norm();
  *normal = gradient / gradient_norm;
  return (g - 1) / gradient_norm;
}

bool DynamicsOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    *why = message;
    return false;
  };
  if (!std::isfinite(time_step_s) || time_step_s <= 0) return fail("time_step_s must be finite and positive");
  if (quadrature_points < 1 || quadrature_points > 5) return fail("quadrature_points must lie in 1..5");
  if (!std::isfinite(air_drag) || air_drag < 0) return fail("air_drag must be finite and >= 0");
  if (!(cg_relative_tolerance > 0) || cg_relative_tolerance >= 1) return fail("cg_relative_tolerance must lie in (0, 1)");
  if (use_head && (!head.radii_m.allFinite() || head.radii_m.minCoeff() <= 0 || !head.center_m.allFinite())) {
    return fail("head radii must be finite and positive and its centre finite");
  }
  if (!std::isfinite(contact_margin_m) || contact_margin_m < 0 || !std::isfinite(contact_stiffness) ||
      contact_stiffness < 0 || !std::isfinite(contact_friction) || contact_friction < 0) {
    return fail("contact margin, stiffness and friction must be finite and >= 0");
  }
  return true;
}

SuperHelixDynamics::SuperHelixDynamics(const SuperHelix& strand, const HairMaterial& material,
                                       const DynamicsOptions& options)
    : strand_(strand), material_(material), options_(options) {
  const int n = strand_.num_elements();
  const Eigen::Vector3d c = material_.Stiffness();
  stiffness_.resize(3 * n);
  std::vector<double> nodes, weights;
  GaussLegendre(options_.quadrature_points, &nodes, &weights);
  for (int e = 0; e < n; ++e) {
    const double length = strand_.lengths_m[static_cast<size_t>(e)];
    stiffness_.segment<3>(3 * e) = length * c;  // V = 1/2 int H^T C^H H ds, H constant per element
    for (size_t k = 0; k < nodes.size(); ++k) samples_.push_back({e, nodes[k] * length, weights[k] * length});
  }
}

// Positions of the quadrature points, without Jacobians.
std::vector<Eigen::Vector3d> SuperHelixDynamics::SamplePositions(const Eigen::VectorXd& q) const {
  const std::vector<ElementFrame> frames = ElementFrames(strand_, q);
  std::vector<Eigen::Vector3d> out;
  out.reserve(samples_.size());
  for (const Sample& sample : samples_) {
    const ElementFrame& f = frames[static_cast<size_t>(sample.element)];
    out.push_back(f.start_m + f.frame * HelixOffset(Eigen::Vector3d::UnitX(), q.segment<3>(3 * sample.element), sample.s));
  }
  return out;
}

// Positions, material frames and Jacobians of the quadrature points. A change
// of element P's coordinates moves the end of P by dX_P and turns it by the
// world rotation dTheta_P; everything beyond P follows rigidly:
//   J_P(r) = dX_P - [r - x_end(P)]x dTheta_P,   J_w,P = dTheta_P.
// Inside its own element the point moves by frame * d offset / d omega and
// turns by frame(s) s J_r(s omega).
void SuperHelixDynamics::Evaluate(const Eigen::VectorXd& q, bool with_jacobians) {
  const int n = strand_.num_elements();
  const int dofs = 3 * n;
  const std::vector<ElementFrame> frames = ElementFrames(strand_, q);
  std::vector<Eigen::Matrix3d> end_move(static_cast<size_t>(n)), end_turn(static_cast<size_t>(n));
  if (with_jacobians) {
    for (int e = 0; e < n; ++e) {
      const Eigen::Vector3d omega = q.segment<3>(3 * e);
      const double length = strand_.lengths_m[static_cast<size_t>(e)];
      end_move[static_cast<size_t>(e)] = frames[static_cast<size_t>(e)].frame * OffsetJacobian(omega, length, length);
      end_turn[static_cast<size_t>(e)] =
          frames[static_cast<size_t>(e) + 1].frame * (length * RightJacobianSO3(length * omega));
    }
  }
  const size_t count = samples_.size();
  positions_.resize(count);
  frames_.resize(count);
  jacobian_.resize(count);
  angular_jacobian_.resize(count);
  for (size_t i = 0; i < count; ++i) {
    const Sample& sample = samples_[i];
    const int e = sample.element;
    const Eigen::Vector3d omega = q.segment<3>(3 * e);
    const ElementFrame& start = frames[static_cast<size_t>(e)];
    positions_[i] = start.start_m + start.frame * HelixOffset(Eigen::Vector3d::UnitX(), omega, sample.s);
    frames_[i] = start.frame * RotationFromVector(sample.s * omega);
    if (!with_jacobians) continue;
    auto& j = jacobian_[i];
    auto& jw = angular_jacobian_[i];
    j.setZero(3, dofs);
    jw.setZero(3, dofs);
    for (int p = 0; p < e; ++p) {
      const Eigen::Vector3d lever = positions_[i] - frames[static_cast<size_t>(p) + 1].start_m;
      j.middleCols<3>(3 * p) = end_move[static_cast<size_t>(p)] - Skew(lever) * end_turn[static_cast<size_t>(p)];
      jw.middleCols<3>(3 * p) = end_turn[static_cast<size_t>(p)];
    }
    j.middleCols<3>(3 * e) = start.frame * OffsetJacobian(omega, sample.s, strand_.lengths_m[static_cast<size_t>(e)]);
    jw.middleCols<3>(3 * e) = frames_[i] * (sample.s * RightJacobianSO3(sample.s * omega));
  }
}

void SuperHelixDynamics::AddProjected(int i, double weight, const Eigen::Matrix3d& metric, Eigen::MatrixXd* out) const {
  const int cols = 3 * (samples_[static_cast<size_t>(i)].element + 1);
  const auto j = jacobian_[static_cast<size_t>(i)].leftCols(cols);
  out->topLeftCorner(cols, cols).noalias() += weight * (j.transpose() * (metric * j));
}

// T_t = 1/2 int rho S |r'|^2 and T_r = 1/2 int rho w^T I w (Sec. VI; the
// paper's K in T_r read as the frame's angular velocity w, with its inertia I).
Eigen::MatrixXd SuperHelixDynamics::MassMatrix() const {
  const int dofs = strand_.num_dofs();
  const double rho_s = material_.LinearDensity();
  const Eigen::Vector3d inertia = material_.density_kg_m3 * material_.SecondMoments();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(dofs, dofs);
  for (size_t i = 0; i < samples_.size(); ++i) {
    const int cols = 3 * (samples_[i].element + 1);
    const double w = samples_[i].weight;
    const auto j = jacobian_[i].leftCols(cols);
    const auto jw = angular_jacobian_[i].leftCols(cols);
    const Eigen::Matrix3d world_inertia = frames_[i] * inertia.asDiagonal() * frames_[i].transpose();
    m.topLeftCorner(cols, cols).noalias() += (w * rho_s) * (j.transpose() * j);
    m.topLeftCorner(cols, cols).noalias() += w * (jw.transpose() * (world_inertia * jw));
  }
  return m;
}

Eigen::Vector3d SuperHelixDynamics::StaticForce(const Environment& env, const Eigen::Vector3d& r) const {
  const double rho_s = material_.LinearDensity();
  const Eigen::Vector3d& w = env.frame_angular_velocity;
  const Eigen::Vector3d arm = r - env.pivot_m;
  // Gravity and the fictitious forces of the frame's motion (all but Coriolis).
  const Eigen::Vector3d frame_acceleration =
      env.frame_acceleration_m_s2 + env.frame_angular_acceleration.cross(arm) + w.cross(w.cross(arm));
  Eigen::Vector3d force = rho_s * (env.gravity_m_s2 - frame_acceleration);
  // Air drag toward the air's velocity relative to the moving frame at r (Eq. 10).
  force += options_.air_drag * (env.air_velocity_m_s - w.cross(arm));
  if (options_.use_head) {
    Eigen::Vector3d normal;
    const double distance = options_.head.Distance(r, &normal);
    if (distance < options_.contact_margin_m) {
      force += options_.contact_stiffness * (options_.contact_margin_m - distance) * normal;
    }
  }
  return force;
}

Eigen::VectorXd SuperHelixDynamics::StaticForces(const Environment& environment, const Eigen::VectorXd& q) {
  Evaluate(q, true);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(strand_.num_dofs());
  for (size_t i = 0; i < samples_.size(); ++i) {
    f.noalias() += samples_[i].weight *
                   (jacobian_[i].transpose() * StaticForce(environment, positions_[i]));
  }
  return f;
}

Eigen::VectorXd SuperHelixDynamics::ElasticForces(const Eigen::VectorXd& q) const {
  return -stiffness_.cwiseProduct(q - strand_.rest_q);
}

// Jacobi-preconditioned conjugate gradient (the paper's solver) or Cholesky.
int SuperHelixDynamics::SolveLinear(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, Eigen::VectorXd* x) const {
  if (options_.solver == LinearSolver::kCholesky) {
    *x = a.llt().solve(b);
    return 1;
  }
  const Eigen::VectorXd inverse_diagonal = a.diagonal().cwiseInverse();
  x->setZero(b.size());
  Eigen::VectorXd r = b;
  Eigen::VectorXd z = inverse_diagonal.cwiseProduct(r);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  const double target = options_.cg_relative_tolerance * options_.cg_relative_tolerance * rz;
  const int max_iterations = 4 * static_cast<int>(b.size()) + 20;
  int iteration = 0;
  while (iteration < max_iterations && rz > target && rz > 0) {
    const Eigen::VectorXd ap = a * p;
    const double alpha = rz / p.dot(ap);
    *x += alpha * p;
    r -= alpha * ap;
    z = inverse_diagonal.cwiseProduct(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
    ++iteration;
  }
  return iteration;
}

Status SuperHelixDynamics::Step(const Environment& env, StrandState* state, StepReport* report) {
  const double h = options_.time_step_s;
  const double theta = options_.integrator == TimeIntegrator::kImplicitEuler ? 1.0 : 0.5;
  const double rho_s = material_.LinearDensity();
  const Eigen::VectorXd& q = state->q;
  const Eigen::VectorXd& v = state->v;
  const int dofs = strand_.num_dofs();

  // J_dot q' at every sample: the second difference of the centreline along q'.
  std::vector<Eigen::Vector3d> velocity_acceleration(samples_.size(), Eigen::Vector3d::Zero());
  const double speed = v.norm();
  if (speed > 0) {
    const double eps = 1e-4 / (speed * std::max(strand_.length_m(), 1e-6));
    const std::vector<Eigen::Vector3d> plus = SamplePositions(q + eps * v);
    const std::vector<Eigen::Vector3d> minus = SamplePositions(q - eps * v);
    const std::vector<Eigen::Vector3d> mid = SamplePositions(q);
    for (size_t i = 0; i < samples_.size(); ++i) {
      velocity_acceleration[i] = (plus[i] - 2 * mid[i] + minus[i]) / (eps * eps);
    }
  }
  Evaluate(q, true);
  const Eigen::MatrixXd mass = MassMatrix();
  Eigen::MatrixXd stiffness = stiffness_.asDiagonal();
  Eigen::MatrixXd damping = (material_.internal_friction_s * stiffness_).asDiagonal();
  Eigen::VectorXd force = Eigen::VectorXd::Zero(dofs);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  int contacts = 0;
  for (size_t i = 0; i < samples_.size(); ++i) {
    const int index = static_cast<int>(i);
    const double w = samples_[i].weight;
    const Eigen::Vector3d velocity = jacobian_[i] * v;
    Eigen::Vector3d f = StaticForce(env, positions_[i]);
    f -= rho_s * (velocity_acceleration[i] + 2 * env.frame_angular_velocity.cross(velocity));
    force.noalias() += w * (jacobian_[i].transpose() * f);
    AddProjected(index, w * options_.air_drag, identity, &damping);
    if (!options_.use_head) continue;
    Eigen::Vector3d normal;
    if (options_.head.Distance(positions_[i], &normal) < options_.contact_margin_m) {
      ++contacts;
      const Eigen::Matrix3d nn = normal * normal.transpose();
      AddProjected(index, w * options_.contact_stiffness, nn, &stiffness);
      AddProjected(index, w * options_.contact_friction, identity - nn, &damping);
    }
  }
  const Eigen::MatrixXd system = mass + (theta * h) * damping + (theta * theta * h * h) * stiffness;
  const Eigen::VectorXd rhs =
      h * (force + ElasticForces(q) - damping * v - (theta * h) * (stiffness * v));
  Eigen::VectorXd dv;
  const int iterations = SolveLinear(system, rhs, &dv);
  if (!dv.allFinite()) {
    return FailedPrecondition("super-helix step: the linear solve gave a non-finite velocity (time step " +
                              std::to_string(h) + " s too large or a degenerate strand)");
  }
  state->q += h * (v + theta * dv);
  state->v += dv;
  if (report) {
    report->solver_iterations = iterations;
    report->contacts = contacts;
  }
  return Status::Ok();
}

StrandEnergy SuperHelixDynamics::Energy(const Environment& env, const StrandState& state) {
  Evaluate(state.q, true);
  StrandEnergy energy;
  energy.kinetic_j = 0.5 * state.v.dot(MassMatrix() * state.v);
  const Eigen::VectorXd strain = state.q - strand_.rest_q;
  energy.elastic_j = 0.5 * strain.dot(stiffness_.cwiseProduct(strain));
  const double rho_s = material_.LinearDensity();
  for (size_t i = 0; i < samples_.size(); ++i) {
    energy.gravity_j -= samples_[i].weight * rho_s * env.gravity_m_s2.dot(positions_[i] - strand_.root_m);
  }
  return energy;
}

}  // namespace hairrig
