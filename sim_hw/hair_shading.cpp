#include "sim_hw/hair_shading.h"

#include <algorithm>
#include <cmath>

#include "core/transform.h"

namespace hairrig {
namespace {

// Lobe weights (radiance per unit irradiance at the lobe's peak is about
// weight * 1 / (beta sqrt(2 pi))): a white primary that nearly saturates a
// correctly exposed frame, a dimmer coloured secondary, strong transmission.
constexpr double kWeightR = 0.15, kWeightTT = 0.45, kWeightTRT = 0.16, kWeightDiffuse = 0.75;
constexpr double kTTAzimuthalWidthRad =
    0.45;  // gamma_TT (Sadeghi et al. 2010: 10-25 deg is typical)

double Gaussian(double beta, double x) {
  return std::exp(-0.5 * x * x / (beta * beta)) / (beta * std::sqrt(2 * kPi));
}

}  // namespace

double PrimaryShiftRad(const HairShading& s) { return DegToRad(s.cuticle_tilt_deg); }
double SecondaryShiftRad(const HairShading& s) { return -1.5 * DegToRad(s.cuticle_tilt_deg); }

FibreRadiance ShadeFibre(const HairShading& s, const Eigen::Vector3d& albedo,
                         const Eigen::Vector3d& t, const Eigen::Vector3d& to_light,
                         const Eigen::Vector3d& to_camera) {
  FibreRadiance out;
  const double sin_i = std::clamp(t.dot(to_light), -1.0, 1.0),
               sin_r = std::clamp(t.dot(to_camera), -1.0, 1.0);
  const double cos_i = std::sqrt(1 - sin_i * sin_i), cos_r = std::sqrt(1 - sin_r * sin_r);
  if (s.model == HairShading::Model::kKajiyaKay) {
    const double specular = 0.35 * std::pow(std::max(0.0, -sin_i * sin_r + cos_i * cos_r), 30.0);
    out.single = Eigen::Vector3d::Constant(specular);
    out.diffuse = 0.9 * cos_i * albedo;
    return out;
  }
  // Longitudinal angles (Marschner Sec. 2.2): theta = asin(t . w), half angle and difference.
  const double theta_i = std::asin(sin_i), theta_r = std::asin(sin_r);
  const double theta_h =
      0.5 * (theta_i + theta_r);  // theta_d = (theta_r - theta_i) / 2 enters as cos^2 below
  // Azimuth between the projections of the two directions onto the normal plane.
  const Eigen::Vector3d li = to_light - sin_i * t, lr = to_camera - sin_r * t;
  const double norms = li.norm() * lr.norm();
  const double cos_phi = norms > 1e-12 ? std::clamp(li.dot(lr) / norms, -1.0, 1.0) : 1.0;
  const double phi = std::acos(cos_phi);  // 0: light and camera on the same side
  // cos(phi / 2) and cos^2(theta_d) by half-angle identities (no further trigonometry).
  const double cos_half_phi = std::sqrt(0.5 * (1 + cos_phi));
  const double cos2_d = 0.5 * (1 + cos_i * cos_r + sin_i * sin_r);
  const double alpha = DegToRad(s.cuticle_tilt_deg), beta = DegToRad(s.roughness_deg);
  const double m_r = Gaussian(beta, theta_h - alpha);
  const double m_tt = Gaussian(0.5 * beta, theta_h + 0.5 * alpha);
  const double m_trt = Gaussian(2 * beta, theta_h + 1.5 * alpha);
  const double n_r = cos_half_phi;
  const double n_tt =
      std::exp(-0.5 * (kPi - phi) * (kPi - phi) / (kTTAzimuthalWidthRad * kTTAzimuthalWidthRad));
  const double inv_cos2_d = 1.0 / std::max(0.2, cos2_d);
  // Colours: the surface reflection is white; light crossing the fibre once
  // (TT) or twice (TRT) takes its colour: sqrt(albedo) per crossing.
  const Eigen::Vector3d once = albedo.cwiseSqrt();
  out.single = inv_cos2_d * cos_i *
               (kWeightR * m_r * n_r * Eigen::Vector3d::Ones() + kWeightTT * m_tt * n_tt * once +
                kWeightTRT * m_trt * n_r * once.cwiseProduct(once));
  out.diffuse = kWeightDiffuse * cos_i * albedo;
  return out;
}

}  // namespace hairrig
