// Super-helix dynamics (Bao & Qi 2017, Sec. VI, Eqs. 9-11; Bertails et al.
// 2006, ref. [3]). The Lagrangian equations of motion (Eq. 9) of one strand in
// its generalised coordinates q (simulation/super_helix.h):
//
//   M(q) q'' + M_dot-terms + D q' + K (q - q^0) = Q(q, q')
//
// with M = int rho S J^T J + rho J_w^T I J_w ds (translational and rotational
// kinetic energy, T_t and T_r), K = diag(C^H L_Q) (potential V), D = mu K
// (dissipation D), Q = int J^T F ds with F = rho S g + F^c - nu r' (Eq. 10).
// The integrals are Gauss-Legendre quadratures per element; J = dr/dq is exact
// up to a central difference inside each element, and the velocity terms
// (J_dot q') come from a second difference of the centreline along q'.
//
// Time step (Eq. 11 and ours):
//   (M + theta h D + theta^2 h^2 K) dv = h [Q - K (q - q^0) - D v - theta h K v]
//   v+ = v + dv,  q+ = q + h (v + theta dv)
// theta = 1 is the paper's linearly implicit Euler step (Eq. 11, dissipative);
// theta = 1/2 is the trapezoidal rule (ours, for energy-conserving runs: the
// velocity terms stay explicit, so it needs a small step, 1/4000 s keeps a
// swinging strand's energy within 0.4 % over 10 s, and it is only
// conditionally stable when high modes are strongly excited). K
// includes the contact stiffness, D the air drag and contact friction, so
// both are implicit. The linear system is solved by conjugate gradient (as the
// paper) or by a dense Cholesky factorisation. M is assembled from moments of
// the points beyond each element, O(N^2) 3 x 3 products per strand.
//
// The simulation frame is the head's: the roots are fixed in it, the head
// may move in the world (head-shake), and the fictitious forces of that motion
// are part of F.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/status.h"
#include "simulation/super_helix.h"

namespace hairrig {

class HeadModel;  // core/head_model.h

enum class TimeIntegrator { kImplicitEuler, kTrapezoidal };
enum class LinearSolver { kConjugateGradient, kCholesky };

// An ellipsoid in the simulation (head) frame, metres.
struct HeadEllipsoid {
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d radii_m = Eigen::Vector3d::Ones();
  // Signed distance estimate (first order in the ellipsoid's implicit
  // function) and outward normal.
  double Distance(const Eigen::Vector3d& p, Eigen::Vector3d* normal) const;
};

struct DynamicsOptions {
  double time_step_s = 1.0 / 240;
  TimeIntegrator integrator = TimeIntegrator::kImplicitEuler;
  // Cholesky is the default: on 1,000 guides of 15 elements it steps 1.4x
  // faster than the paper's Jacobi-preconditioned CG (about 47 iterations for
  // 45 unknowns), with the same result (bench/dynamics_bench.cpp).
  LinearSolver solver = LinearSolver::kCholesky;
  double cg_relative_tolerance = 1e-10;
  int quadrature_points = 3;  // Gauss-Legendre points per element (1-5)
  double air_drag = 1e-4;     // nu of Eq. 10, N s / m^2 (force per length per velocity)
  bool use_head = false;
  HeadEllipsoid head;
  // When set (with use_head), contact is with this head's surface (its
  // signed distance; mm in the same frame as the simulation's metres)
  // instead of the ellipsoid: the head strands were reconstructed or grown on.
  std::shared_ptr<const HeadModel> head_surface;
  double contact_margin_m = 0.5e-3;  // hair keeps this far from the head
  double contact_stiffness = 50;     // N / m^2: force per length per metre of penetration
  double contact_friction = 2e-3;    // viscous friction along the head, N s / m^2

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

// What the world does to the strands at one instant, in the simulation frame.
struct Environment {
  Eigen::Vector3d gravity_m_s2{0, 0, -9.81};
  // Air velocity relative to the frame at the pivot (wind minus the pivot's motion).
  Eigen::Vector3d air_velocity_m_s = Eigen::Vector3d::Zero();
  // Motion of the simulation frame in the world, expressed in the frame: the
  // pivot (a point of the frame the rotation is about), its acceleration, and
  // the frame's angular velocity and acceleration.
  Eigen::Vector3d pivot_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d frame_acceleration_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d frame_angular_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d frame_angular_acceleration = Eigen::Vector3d::Zero();
};

struct StrandState {
  Eigen::VectorXd q;  // rad/m
  Eigen::VectorXd v;  // q', rad/(m s)
};

struct StepReport {
  int solver_iterations = 0;
  int contacts = 0;  // quadrature points in contact with the head
};

struct StrandEnergy {
  double kinetic_j = 0;
  double elastic_j = 0;
  double gravity_j = 0;  // relative to the root's height
  double total() const { return kinetic_j + elastic_j + gravity_j; }
};

// One strand's equations of motion. Not thread-safe (holds work buffers); use
// one per thread or per strand.
class SuperHelixDynamics {
 public:
  SuperHelixDynamics(const SuperHelix& strand, const HairMaterial& material,
                     const DynamicsOptions& options);

  // Advances `state` by one time step. FailedPrecondition if the state is not
  // finite after the step (the state is left unchanged).
  Status Step(const Environment& environment, StrandState* state, StepReport* report = nullptr);

  // Samples that rest nearer the head than contact_margin_m in `q_rest` (or
  // inside it, as a fitted strand lying on the head can) get their rest
  // distance as their margin: the rest state carries no contact force, and
  // no sample is pushed further in than where it rests. Without this call
  // every sample keeps contact_margin_m. No effect without use_head.
  void HoldContactAtRest(const Eigen::VectorXd& q_rest);

  // Generalised forces Q of gravity and contact at rest (q' = 0).
  Eigen::VectorXd StaticForces(const Environment& environment, const Eigen::VectorXd& q);
  Eigen::VectorXd ElasticForces(const Eigen::VectorXd& q) const;  // -K (q - q^0)
  const Eigen::VectorXd& StiffnessDiagonal() const { return stiffness_; }

  StrandEnergy Energy(const Environment& environment, const StrandState& state);

  const SuperHelix& strand() const { return strand_; }
  SuperHelix& mutable_strand() { return strand_; }

 private:
  struct Sample {
    int element = 0;
    double s = 0;       // arc length within the element
    double weight = 0;  // quadrature weight, m
  };
  void Evaluate(const Eigen::VectorXd& q);
  std::vector<Eigen::Vector3d> SamplePositions(const Eigen::VectorXd& q) const;
  // Force per unit length at sample i (positions_ from Evaluate) at rest
  // (gravity, frame motion, wind, contact).
  Eigen::Vector3d StaticForce(const Environment& environment, size_t sample) const;
  // Signed distance (m) to the head and its outward normal at p (m).
  double HeadDistance(const Eigen::Vector3d& p_m, Eigen::Vector3d* normal) const;
  // The kinetic metric in two parts: int J^T J ds (translational, without
  // rho S) and int rho J_w^T I J_w ds (rotational).
  void KineticMetrics(Eigen::MatrixXd* translational, Eigen::MatrixXd* rotational) const;
  // Q = int J^T F ds for per-sample forces per unit length.
  Eigen::VectorXd GeneralisedForce(const std::vector<Eigen::Vector3d>& force_per_m) const;
  std::vector<Eigen::Vector3d> SampleVelocities(const Eigen::VectorXd& v) const;
  // out += weight * J_i^T metric J_i over the columns sample i depends on.
  void AddProjected(int i, double weight, const Eigen::Matrix3d& metric,
                    Eigen::MatrixXd* out) const;
  int SolveLinear(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, Eigen::VectorXd* x) const;

  SuperHelix strand_;
  HairMaterial material_;
  DynamicsOptions options_;
  Eigen::VectorXd stiffness_;  // diagonal of K
  std::vector<Sample> samples_;
  std::vector<int> first_sample_;         // per element, and one past the last sample
  std::vector<double> contact_margin_m_;  // per sample (HoldContactAtRest)
  Eigen::VectorXd previous_dv_;           // warm start of the conjugate gradient
  // Filled by Evaluate(q). Per element p, for any point r beyond it:
  //   dr/dq_p = move_[p] - [r]x turn_[p],  its frame turns by turn_[p] dq_p.
  std::vector<Eigen::Matrix3d> move_, turn_;
  // Per sample: position, material frame, and dr/dq, dtheta/dq for its own element.
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Eigen::Matrix3d> frames_;
  std::vector<Eigen::Matrix3d> local_jacobian_;
  std::vector<Eigen::Matrix3d> local_angular_jacobian_;
};

}  // namespace hairrig
