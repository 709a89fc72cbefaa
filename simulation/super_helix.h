// The super-helix strand of Bao & Qi 2017, Sec. VI (after Bertails et al.,
// "Super-Helices", ref. [3]): N elements, each with a constant material
// Darboux vector q_Q = (twist, curvature 1, curvature 2) in its material frame
// (tangent, n1, n2), so that each element is a helix and the strand is G1 with a
// continuous material frame. The root is clamped: its position and frame are
// given. The generalised coordinates q (3N) and their rates q' are the state of
// the dynamics (simulation/super_helix_dynamics.h).
//
// Units: SI inside the dynamics (metres, kilograms, seconds, radians per
// metre); conversions from the millimetre strands and helix models are here.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "simulation/floating_tangents.h"

namespace hairrig {

// A hair fibre (Sec. VI): elliptic cross-section of semi-axes a1 >= a2,
// Poisson ratio 0.48. Defaults are a single human hair (density and modulus as
// in Bertails et al. 2006, ref. [3]; semi-axes 50 and 40 micrometres).
struct HairMaterial {
  double density_kg_m3 = 1300;
  double youngs_modulus_pa = 3.9e9;
  double poisson_ratio = 0.48;
  double semi_axis_1_m = 50e-6;  // a1
  double semi_axis_2_m = 40e-6;  // a2
  // mu of the dissipation energy D (Sec. VI), seconds: D = 1/2 mu K'^T C K'.
  // The paper uses 0.1.
  double internal_friction_s = 0.1;

  double LinearDensity() const;  // rho S, kg/m
  // I_0 (twist, with the 1 / (2 (1 + sigma)) of the shear modulus folded in as
  // in the paper), I_1, I_2 (bending); m^4.
  Eigen::Vector3d SecondMoments() const;
  // C^H = E (I_0, I_1, I_2): twist and bending stiffness, N m^2.
  Eigen::Vector3d Stiffness() const { return youngs_modulus_pa * SecondMoments(); }
  // InvalidArgument naming the first field that is not finite and positive.
  Status Check() const;
};

struct SuperHelix {
  Eigen::Vector3d root_m = Eigen::Vector3d::Zero();
  // World from material frame at the root: columns tangent, n1, n2.
  Eigen::Matrix3d root_frame = Eigen::Matrix3d::Identity();
  std::vector<double> lengths_m;  // per element, > 0
  Eigen::VectorXd rest_q;         // q^0: intrinsic twist and curvatures, rad/m, size 3N

  int num_elements() const { return static_cast<int>(lengths_m.size()); }
  int num_dofs() const { return 3 * num_elements(); }
  double length_m() const;
};

// Where an element starts: its root point and material frame (world from material).
struct ElementFrame {
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
};

// The helical recursion: the start frame of every element and the end of the
// strand (N + 1 frames) for coordinates q.
std::vector<ElementFrame> ElementFrames(const SuperHelix& strand, const Eigen::VectorXd& q);

// Points along the centreline, `per_element` per element plus the root, metres.
std::vector<Eigen::Vector3d> Centreline(const SuperHelix& strand, const Eigen::VectorXd& q,
                                        int per_element);
Eigen::Vector3d TipPosition(const SuperHelix& strand, const Eigen::VectorXd& q);

// Rotation by the body-frame rotation vector phi (Rodrigues) and the right
// Jacobian of SO(3) at phi: exp(phi + d) ~ exp(phi) exp(J_r(phi) d).
Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& phi);
Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi);

// A fitted guide (millimetres, world Darboux vectors) as a super-helix with
// its coordinates; the rest shape is the fitted shape (q^0 = q) until inverse
// statics changes it. `root_normal_hint` fixes n1 at the root (any direction
// not along the root tangent). InvalidArgument for an empty or degenerate guide.
Result<SuperHelix> SuperHelixFromPiecewiseHelix(const PiecewiseHelix& guide,
                                                const Eigen::Vector3d& root_normal_hint,
                                                Eigen::VectorXd* q);

}  // namespace hairrig
