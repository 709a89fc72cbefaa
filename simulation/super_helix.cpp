#include "simulation/super_helix.h"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "core/transform.h"
#include "simulation/helix.h"

namespace hairrig {

double HairMaterial::LinearDensity() const {
  return density_kg_m3 * kPi * semi_axis_1_m * semi_axis_2_m;
}

// Sec. VI: I_0 = pi a1^3 a2^3 / (2 (1 + sigma) (a1^2 + a2^2)), I_1 = pi/4 a1 a2^3, I_2 = pi/4 a1^3
// a2.
Eigen::Vector3d HairMaterial::SecondMoments() const {
  const double a1 = semi_axis_1_m;
  const double a2 = semi_axis_2_m;
  const double i0 =
      kPi * a1 * a1 * a1 * a2 * a2 * a2 / (2 * (1 + poisson_ratio) * (a1 * a1 + a2 * a2));
  return {i0, kPi / 4 * a1 * a2 * a2 * a2, kPi / 4 * a1 * a1 * a1 * a2};
}

Status HairMaterial::Check() const {
  const std::pair<const char*, double> fields[] = {{"density_kg_m3", density_kg_m3},
                                                   {"youngs_modulus_pa", youngs_modulus_pa},
                                                   {"semi_axis_1_m", semi_axis_1_m},
                                                   {"semi_axis_2_m", semi_axis_2_m}};
  for (const auto& [name, value] : fields) {
    if (!std::isfinite(value) || value <= 0) {
      return InvalidArgument(std::string("hair material: ") + name +
                             " must be finite and positive, got " + std::to_string(value));
    }
  }
  if (!std::isfinite(poisson_ratio) || poisson_ratio <= -1 || poisson_ratio >= 0.5) {
    return InvalidArgument("hair material: poisson_ratio must lie in (-1, 0.5), got " +
                           std::to_string(poisson_ratio));
  }
  if (!std::isfinite(internal_friction_s) || internal_friction_s < 0) {
    return InvalidArgument("hair material: internal_friction_s must be finite and >= 0");
  }
  return Status::Ok();
}

double SuperHelix::length_m() const {
  double total = 0;
  for (double l : lengths_m) total += l;
  return total;
}

Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity() + CrossMatrix(phi);
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi) {
  const double t = phi.norm();
  const Eigen::Matrix3d k = CrossMatrix(phi);
  double a;  // (1 - cos t) / t^2
  double b;  // (t - sin t) / t^3
  if (t < 1e-4) {
    a = 0.5 - t * t / 24;
    b = 1.0 / 6 - t * t / 120;
  } else {
    a = (1 - std::cos(t)) / (t * t);
    b = (t - std::sin(t)) / (t * t * t);
  }
  return Eigen::Matrix3d::Identity() - a * k + b * k * k;
}

// Within an element the material frame turns with the constant body-frame
// Darboux vector q_Q: frame(s) = frame(0) exp(s [q_Q]x), and the centreline is
// the helix of Eq. 8 with tangent e_1 in the material frame.
std::vector<ElementFrame> ElementFrames(const SuperHelix& strand, const Eigen::VectorXd& q) {
  std::vector<ElementFrame> frames(static_cast<size_t>(strand.num_elements()) + 1);
  frames[0].start_m = strand.root_m;
  frames[0].frame = strand.root_frame;
  for (int e = 0; e < strand.num_elements(); ++e) {
    const Eigen::Vector3d omega = q.segment<3>(3 * e);
    const double length = strand.lengths_m[static_cast<size_t>(e)];
    const ElementFrame& start = frames[static_cast<size_t>(e)];
    ElementFrame& end = frames[static_cast<size_t>(e) + 1];
    end.start_m =
        start.start_m + start.frame * HelixOffset(Eigen::Vector3d::UnitX(), omega, length);
    end.frame = start.frame * RotationFromVector(length * omega);
  }
  return frames;
}

std::vector<Eigen::Vector3d> Centreline(const SuperHelix& strand, const Eigen::VectorXd& q,
                                        int per_element) {
  const std::vector<ElementFrame> frames = ElementFrames(strand, q);
  std::vector<Eigen::Vector3d> points{strand.root_m};
  for (int e = 0; e < strand.num_elements(); ++e) {
    const Eigen::Vector3d omega = q.segment<3>(3 * e);
    const double length = strand.lengths_m[static_cast<size_t>(e)];
    for (int i = 1; i <= per_element; ++i) {
      const double s = length * i / per_element;
      points.push_back(frames[static_cast<size_t>(e)].start_m +
                       frames[static_cast<size_t>(e)].frame *
                           HelixOffset(Eigen::Vector3d::UnitX(), omega, s));
    }
  }
  return points;
}

Eigen::Vector3d TipPosition(const SuperHelix& strand, const Eigen::VectorXd& q) {
  return ElementFrames(strand, q).back().start_m;
}

Result<SuperHelix> SuperHelixFromPiecewiseHelix(const PiecewiseHelix& guide,
                                                const Eigen::Vector3d& root_normal_hint,
                                                Eigen::VectorXd* q) {
  if (guide.elements.empty())
    return InvalidArgument("super-helix: the guide has no helical element");
  const Eigen::Vector3d t0 = guide.elements[0].start_tangent.normalized();
  Eigen::Vector3d n1 = root_normal_hint - root_normal_hint.dot(t0) * t0;
  if (n1.norm() < 1e-6) n1 = t0.unitOrthogonal();
  n1.normalize();
  SuperHelix strand;
  strand.root_m = 1e-3 * guide.elements[0].start_mm;
  strand.root_frame.col(0) = t0;
  strand.root_frame.col(1) = n1;
  strand.root_frame.col(2) = t0.cross(n1);
  const int n = static_cast<int>(guide.elements.size());
  q->resize(3 * n);
  Eigen::Matrix3d frame = strand.root_frame;
  for (int e = 0; e < n; ++e) {
    const HelixElement& h = guide.elements[static_cast<size_t>(e)];
    if (!(h.length_mm > 0) || !std::isfinite(h.length_mm) || !h.darboux_per_mm.allFinite()) {
      return InvalidArgument("super-helix: element " + std::to_string(e) +
                             " has a non-positive or non-finite length or Darboux vector");
    }
    // The world Darboux vector in the element's material frame, per metre.
    const Eigen::Vector3d omega = 1e3 * frame.transpose() * h.darboux_per_mm;
    q->segment<3>(3 * e) = omega;
    strand.lengths_m.push_back(1e-3 * h.length_mm);
    frame = frame * RotationFromVector(strand.lengths_m.back() * omega);
  }
  strand.rest_q = *q;
  return strand;
}

}  // namespace hairrig
