#include "simulation/super_helix_dynamics.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "core/head_model.h"
#include "simulation/helix.h"

namespace hairrig {

namespace {

// Gauss-Legendre nodes on [0, 1] and weights summing to 1.
void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  static const double kNodes[5][5] = {
      {0},
      {-0.5773502691896257, 0.5773502691896257},
      {-0.7745966692414834, 0, 0.7745966692414834},
      {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526},
      {-0.9061798459386640, -0.5384693101056831, 0, 0.5384693101056831, 0.9061798459386640}};
  static const double kWeights[5][5] = {
      {2},
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
    d.col(j) = (HelixOffset(Eigen::Vector3d::UnitX(), plus, s) -
                HelixOffset(Eigen::Vector3d::UnitX(), minus, s)) /
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

Status DynamicsOptions::Check() const {
  if (!std::isfinite(time_step_s) || time_step_s <= 0)
    return InvalidArgument("time_step_s must be finite and positive");
  if (quadrature_points < 1 || quadrature_points > 5)
    return InvalidArgument("quadrature_points must lie in 1..5");
  if (!std::isfinite(air_drag) || air_drag < 0)
    return InvalidArgument("air_drag must be finite and >= 0");
  if (!(cg_relative_tolerance > 0) || cg_relative_tolerance >= 1)
    return InvalidArgument("cg_relative_tolerance must lie in (0, 1)");
  if (use_head && (!head.radii_m.allFinite() || head.radii_m.minCoeff() <= 0))
    return InvalidArgument("head.radii_m must be finite and positive");
  if (use_head && !head.center_m.allFinite())
    return InvalidArgument("head.center_m must be finite");
  if (!std::isfinite(contact_margin_m) || contact_margin_m < 0)
    return InvalidArgument("contact_margin_m must be finite and >= 0");
  if (!std::isfinite(contact_stiffness) || contact_stiffness < 0)
    return InvalidArgument("contact_stiffness must be finite and >= 0");
  if (!std::isfinite(contact_friction) || contact_friction < 0)
    return InvalidArgument("contact_friction must be finite and >= 0");
  return Status::Ok();
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
    first_sample_.push_back(static_cast<int>(samples_.size()));
    for (size_t k = 0; k < nodes.size(); ++k)
      samples_.push_back({e, nodes[k] * length, weights[k] * length});
  }
  first_sample_.push_back(static_cast<int>(samples_.size()));
  contact_margin_m_.assign(samples_.size(), options_.contact_margin_m);
}

void SuperHelixDynamics::HoldContactAtRest(const Eigen::VectorXd& q_rest) {
  if (!options_.use_head) return;
  const std::vector<Eigen::Vector3d> rest = SamplePositions(q_rest);
  for (size_t i = 0; i < rest.size(); ++i) {
    Eigen::Vector3d normal;
    contact_margin_m_[i] = std::min(options_.contact_margin_m, HeadDistance(rest[i], &normal));
  }
}

// Positions of the quadrature points, without Jacobians.
std::vector<Eigen::Vector3d> SuperHelixDynamics::SamplePositions(const Eigen::VectorXd& q) const {
  const std::vector<ElementFrame> frames = ElementFrames(strand_, q);
  std::vector<Eigen::Vector3d> out;
  out.reserve(samples_.size());
  for (const Sample& sample : samples_) {
    const ElementFrame& f = frames[static_cast<size_t>(sample.element)];
    out.push_back(f.start_m + f.frame * HelixOffset(Eigen::Vector3d::UnitX(),
                                                    q.segment<3>(3 * sample.element), sample.s));
  }
  return out;
}

// Positions, material frames and Jacobians of the quadrature points. A change
// of element P's coordinates moves the end of P by dX_P and turns it by the
// world rotation B_P; everything beyond P follows rigidly:
//   dr/dq_P = dX_P - [r - x_end(P)]x B_P = C_P - [r]x B_P,  C_P = dX_P + [x_end(P)]x B_P,
// and its frame turns by B_P. Inside its own element a point moves by
// frame * d offset / d omega and turns by frame(s) s J_r(s omega).
void SuperHelixDynamics::Evaluate(const Eigen::VectorXd& q) {
  const int n = strand_.num_elements();
  const std::vector<ElementFrame> frames = ElementFrames(strand_, q);
  move_.resize(static_cast<size_t>(n));
  turn_.resize(static_cast<size_t>(n));
  const size_t count = samples_.size();
  positions_.resize(count);
  frames_.resize(count);
  local_jacobian_.resize(count);
  local_angular_jacobian_.resize(count);
  for (int e = 0; e < n; ++e) {
    const size_t ue = static_cast<size_t>(e);
    const Eigen::Vector3d omega = q.segment<3>(3 * e);
    const double length = strand_.lengths_m[ue];
    const ElementFrame& start = frames[ue];
    turn_[ue] = frames[ue + 1].frame * (length * RightJacobianSO3(length * omega));
    move_[ue] = start.frame * OffsetJacobian(omega, length, length) +
                CrossMatrix(frames[ue + 1].start_m) * turn_[ue];
    for (int i = first_sample_[ue]; i < first_sample_[ue + 1]; ++i) {
      const size_t ui = static_cast<size_t>(i);
      const double s = samples_[ui].s;
      positions_[ui] =
          start.start_m + start.frame * HelixOffset(Eigen::Vector3d::UnitX(), omega, s);
      frames_[ui] = start.frame * RotationFromVector(s * omega);
      local_jacobian_[ui] = start.frame * OffsetJacobian(omega, s, length);
      local_angular_jacobian_[ui] = frames_[ui] * (s * RightJacobianSO3(s * omega));
    }
  }
}

void SuperHelixDynamics::AddProjected(int i, double weight, const Eigen::Matrix3d& metric,
                                      Eigen::MatrixXd* out) const {
  const size_t ui = static_cast<size_t>(i);
  const int e = samples_[ui].element;
  Eigen::Matrix<double, 3, Eigen::Dynamic> j(3, 3 * (e + 1));
  const Eigen::Matrix3d lever = CrossMatrix(positions_[ui]);
  for (int p = 0; p < e; ++p) {
    j.middleCols<3>(3 * p) = move_[static_cast<size_t>(p)] - lever * turn_[static_cast<size_t>(p)];
  }
  j.middleCols<3>(3 * e) = local_jacobian_[ui];
  const int cols = 3 * (e + 1);
  out->topLeftCorner(cols, cols).noalias() += weight * (j.transpose() * (metric * j));
}

// T_t = 1/2 int rho S |r'|^2 and T_r = 1/2 int rho w^T I w (Sec. VI; the
// paper's K in T_r read as the frame's angular velocity w, with its inertia I).
// Block (p, q), p < q, sums over the points beyond q, where both Jacobians are
// rigid (C - [r]x B), and over q's own points. With the moments of the points
// beyond q, m0 = int 1, m1 = int r, m2 = int [r]x^T [r]x, W = int rho I_world,
// and P = int J_q, Q = int [r]x J_q, V = int rho I_world J_w,q over q's points:
//   T_pq = C_p^T (m0 C_q - [m1]x B_q + P) + B_p^T ([m1]x C_q + m2 B_q + Q),
//   R_pq = B_p^T (W B_q + V),
// so assembling M costs O(N^2) 3 x 3 products instead of O(N^2) per point.
void SuperHelixDynamics::KineticMetrics(Eigen::MatrixXd* translational,
                                        Eigen::MatrixXd* rotational) const {
  const int n = strand_.num_elements();
  const Eigen::Vector3d inertia = material_.density_kg_m3 * material_.SecondMoments();
  translational->setZero(3 * n, 3 * n);
  rotational->setZero(3 * n, 3 * n);
  double m0 = 0;
  Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d w_beyond = Eigen::Matrix3d::Zero();
  for (int q = n - 1; q >= 0; --q) {
    const size_t uq = static_cast<size_t>(q);
    Eigen::Matrix3d p_sum = Eigen::Matrix3d::Zero(), q_sum = Eigen::Matrix3d::Zero(),
                    v_sum = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d t_own = Eigen::Matrix3d::Zero(), r_own = Eigen::Matrix3d::Zero(),
                    w_own = Eigen::Matrix3d::Zero();
    double m0_own = 0;
    Eigen::Vector3d m1_own = Eigen::Vector3d::Zero();
    Eigen::Matrix3d m2_own = Eigen::Matrix3d::Zero();
    for (int i = first_sample_[uq]; i < first_sample_[uq + 1]; ++i) {
      const size_t ui = static_cast<size_t>(i);
      const double w = samples_[ui].weight;
      const Eigen::Vector3d& r = positions_[ui];
      const Eigen::Matrix3d& j = local_jacobian_[ui];
      const Eigen::Matrix3d& jw = local_angular_jacobian_[ui];
      const Eigen::Matrix3d world_inertia =
          frames_[ui] * inertia.asDiagonal() * frames_[ui].transpose();
      p_sum += w * j;
      q_sum += w * CrossMatrix(r) * j;
      v_sum += w * world_inertia * jw;
      t_own += w * j.transpose() * j;
      r_own += w * jw.transpose() * world_inertia * jw;
      m0_own += w;
      m1_own += w * r;
      m2_own += w * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      w_own += w * world_inertia;
    }
    const Eigen::Matrix3d& b = turn_[uq];
    const Eigen::Matrix3d& c = move_[uq];
    const Eigen::Matrix3d g_beyond = m0 * c - CrossMatrix(m1) * b;
    const Eigen::Matrix3d h_beyond = CrossMatrix(m1) * c + m2 * b;
    translational->block<3, 3>(3 * q, 3 * q) =
        c.transpose() * g_beyond + b.transpose() * h_beyond + t_own;
    rotational->block<3, 3>(3 * q, 3 * q) = b.transpose() * w_beyond * b + r_own;
    const Eigen::Matrix3d g = g_beyond + p_sum;
    const Eigen::Matrix3d h = h_beyond + q_sum;
    const Eigen::Matrix3d k = w_beyond * b + v_sum;
    for (int p = 0; p < q; ++p) {
      const size_t up = static_cast<size_t>(p);
      const Eigen::Matrix3d t_pq = move_[up].transpose() * g + turn_[up].transpose() * h;
      const Eigen::Matrix3d r_pq = turn_[up].transpose() * k;
      translational->block<3, 3>(3 * p, 3 * q) = t_pq;
      translational->block<3, 3>(3 * q, 3 * p) = t_pq.transpose();
      rotational->block<3, 3>(3 * p, 3 * q) = r_pq;
      rotational->block<3, 3>(3 * q, 3 * p) = r_pq.transpose();
    }
    m0 += m0_own;
    m1 += m1_own;
    m2 += m2_own;
    w_beyond += w_own;
  }
}

// Q_p = C_p^T int F + B_p^T int r x F over the points beyond p, plus p's own points.
Eigen::VectorXd SuperHelixDynamics::GeneralisedForce(
    const std::vector<Eigen::Vector3d>& force_per_m) const {
  const int n = strand_.num_elements();
  Eigen::VectorXd f(3 * n);
  Eigen::Vector3d force_beyond = Eigen::Vector3d::Zero(), torque_beyond = Eigen::Vector3d::Zero();
  for (int q = n - 1; q >= 0; --q) {
    const size_t uq = static_cast<size_t>(q);
    Eigen::Vector3d own =
        move_[uq].transpose() * force_beyond + turn_[uq].transpose() * torque_beyond;
    for (int i = first_sample_[uq]; i < first_sample_[uq + 1]; ++i) {
      const size_t ui = static_cast<size_t>(i);
      const Eigen::Vector3d weighted = samples_[ui].weight * force_per_m[ui];
      own += local_jacobian_[ui].transpose() * weighted;
      force_beyond += weighted;
      torque_beyond += positions_[ui].cross(weighted);
    }
    f.segment<3>(3 * q) = own;
  }
  return f;
}

// r' = sum over earlier elements of (C_p q'_p + (B_p q'_p) x r), plus the own element's term.
std::vector<Eigen::Vector3d> SuperHelixDynamics::SampleVelocities(const Eigen::VectorXd& v) const {
  std::vector<Eigen::Vector3d> out(samples_.size());
  Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
  for (int e = 0; e < strand_.num_elements(); ++e) {
    const size_t ue = static_cast<size_t>(e);
    const Eigen::Vector3d ve = v.segment<3>(3 * e);
    for (int i = first_sample_[ue]; i < first_sample_[ue + 1]; ++i) {
      const size_t ui = static_cast<size_t>(i);
      out[ui] = linear + angular.cross(positions_[ui]) + local_jacobian_[ui] * ve;
    }
    linear += move_[ue] * ve;
    angular += turn_[ue] * ve;
  }
  return out;
}

Eigen::Vector3d SuperHelixDynamics::StaticForce(const Environment& env, size_t sample) const {
  const Eigen::Vector3d& r = positions_[sample];
  const double rho_s = material_.LinearDensity();
  const Eigen::Vector3d& w = env.frame_angular_velocity;
  const Eigen::Vector3d arm = r - env.pivot_m;
  // Gravity and the fictitious forces of the frame's motion (all but Coriolis).
  const Eigen::Vector3d frame_acceleration = env.frame_acceleration_m_s2 +
                                             env.frame_angular_acceleration.cross(arm) +
                                             w.cross(w.cross(arm));
  Eigen::Vector3d force = rho_s * (env.gravity_m_s2 - frame_acceleration);
  // Air drag toward the air's velocity relative to the moving frame at r (Eq. 10).
  force += options_.air_drag * (env.air_velocity_m_s - w.cross(arm));
  if (options_.use_head) {
    Eigen::Vector3d normal;
    const double distance = HeadDistance(r, &normal);
    if (distance < contact_margin_m_[sample]) {
      force += options_.contact_stiffness * (contact_margin_m_[sample] - distance) * normal;
    }
  }
  return force;
}

double SuperHelixDynamics::HeadDistance(const Eigen::Vector3d& p_m, Eigen::Vector3d* normal) const {
  if (!options_.head_surface) return options_.head.Distance(p_m, normal);
  return 1e-3 * options_.head_surface->SignedDistance(1e3 * p_m, normal);
}

Eigen::VectorXd SuperHelixDynamics::StaticForces(const Environment& environment,
                                                 const Eigen::VectorXd& q) {
  Evaluate(q);
  std::vector<Eigen::Vector3d> forces(samples_.size());
  for (size_t i = 0; i < samples_.size(); ++i) forces[i] = StaticForce(environment, i);
  return GeneralisedForce(forces);
}

Eigen::VectorXd SuperHelixDynamics::ElasticForces(const Eigen::VectorXd& q) const {
  return -stiffness_.cwiseProduct(q - strand_.rest_q);
}

// Jacobi-preconditioned conjugate gradient (the paper's solver) or Cholesky.
int SuperHelixDynamics::SolveLinear(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                                    Eigen::VectorXd* x) const {
  if (options_.solver == LinearSolver::kCholesky) {
    *x = a.llt().solve(b);
    return 1;
  }
  const Eigen::VectorXd inverse_diagonal = a.diagonal().cwiseInverse();
  // Warm start from the previous step's velocity change: successive steps differ little.
  if (previous_dv_.size() == b.size()) {
    *x = previous_dv_;
  } else {
    x->setZero(b.size());
  }
  Eigen::VectorXd r = b - a * *x;
  Eigen::VectorXd z = inverse_diagonal.cwiseProduct(r);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  const double b_norm = b.dot(inverse_diagonal.cwiseProduct(b));
  const double target = options_.cg_relative_tolerance * options_.cg_relative_tolerance * b_norm;
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

  Evaluate(q);
  // J_dot q' at every sample: the second difference of the centreline along q'.
  std::vector<Eigen::Vector3d> velocity_acceleration(samples_.size(), Eigen::Vector3d::Zero());
  const double speed = v.norm();
  if (speed > 0) {
    const double eps = 1e-4 / (speed * std::max(strand_.length_m(), 1e-6));
    const std::vector<Eigen::Vector3d> plus = SamplePositions(q + eps * v);
    const std::vector<Eigen::Vector3d> minus = SamplePositions(q - eps * v);
    for (size_t i = 0; i < samples_.size(); ++i) {
      velocity_acceleration[i] = (plus[i] - 2 * positions_[i] + minus[i]) / (eps * eps);
    }
  }
  Eigen::MatrixXd translational, rotational;
  KineticMetrics(&translational, &rotational);
  const Eigen::MatrixXd mass = rho_s * translational + rotational;
  Eigen::MatrixXd stiffness = stiffness_.asDiagonal();
  Eigen::MatrixXd damping = options_.air_drag * translational;  // drag -nu r', implicit
  damping.diagonal() += material_.internal_friction_s * stiffness_;
  const std::vector<Eigen::Vector3d> velocities = SampleVelocities(v);
  std::vector<Eigen::Vector3d> forces(samples_.size());
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  int contacts = 0;
  for (size_t i = 0; i < samples_.size(); ++i) {
    forces[i] = StaticForce(env, i) - rho_s * (velocity_acceleration[i] +
                                               2 * env.frame_angular_velocity.cross(velocities[i]));
    if (!options_.use_head) continue;
    Eigen::Vector3d normal;
    if (HeadDistance(positions_[i], &normal) < contact_margin_m_[i]) {
      ++contacts;
      const Eigen::Matrix3d nn = normal * normal.transpose();
      const double w = samples_[i].weight;
      AddProjected(static_cast<int>(i), w * options_.contact_stiffness, nn, &stiffness);
      AddProjected(static_cast<int>(i), w * options_.contact_friction, identity - nn, &damping);
    }
  }
  const Eigen::VectorXd force = GeneralisedForce(forces);
  const Eigen::MatrixXd system = mass + (theta * h) * damping + (theta * theta * h * h) * stiffness;
  const Eigen::VectorXd rhs =
      h * (force + ElasticForces(q) - damping * v - (theta * h) * (stiffness * v));
  Eigen::VectorXd dv;
  const int iterations = SolveLinear(system, rhs, &dv);
  if (!dv.allFinite()) {
    return FailedPrecondition(
        "super-helix step: the linear solve gave a non-finite velocity (time step " +
        std::to_string(h) + " s too large or a degenerate strand)");
  }
  previous_dv_ = dv;
  state->q += h * (v + theta * dv);
  state->v += dv;
  if (report) {
    report->solver_iterations = iterations;
    report->contacts = contacts;
  }
  return Status::Ok();
}

StrandEnergy SuperHelixDynamics::Energy(const Environment& env, const StrandState& state) {
  Evaluate(state.q);
  Eigen::MatrixXd translational, rotational;
  KineticMetrics(&translational, &rotational);
  StrandEnergy energy;
  energy.kinetic_j =
      0.5 * state.v.dot((material_.LinearDensity() * translational + rotational) * state.v);
  const Eigen::VectorXd strain = state.q - strand_.rest_q;
  energy.elastic_j = 0.5 * strain.dot(stiffness_.cwiseProduct(strain));
  const double rho_s = material_.LinearDensity();
  for (size_t i = 0; i < samples_.size(); ++i) {
    energy.gravity_j -=
        samples_[i].weight * rho_s * env.gravity_m_s2.dot(positions_[i] - strand_.root_m);
  }
  return energy;
}

}  // namespace hairrig
