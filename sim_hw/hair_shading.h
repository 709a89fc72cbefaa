// Light scattered by one hair fibre towards the camera, for the simulated
// rig's renderer. Directions are unit vectors in one frame (any); the tangent
// points from root to tip.
//
// kMarschner follows Marschner et al. 2003 ("Light scattering from human hair
// fibers", Sec. 4): three lobes, R (reflection at the surface: white), TT
// (transmission through the fibre: the fibre's colour, seen with the light
// behind) and TRT (one internal reflection: the coloured secondary highlight),
// each a longitudinal Gaussian M_p(theta_h - alpha_p) of width beta_p times an
// azimuthal term N_p(phi), divided by cos^2(theta_d) (their Eq. 5). The
// azimuthal terms are the simplified forms of Sadeghi et al. 2010 ("An artist
// friendly hair shading system", Sec. 4.2): N_R = N_TRT = cos(phi/2), N_TT a
// Gaussian around phi = pi. Multiple scattering inside the hair volume, which
// gives hair most of its colour, is a diffuse term proportional to the fibre's
// albedo and the sine of the light's angle to the fibre. kKajiyaKay is Kajiya
// & Kay 1989 (one diffuse and one specular lobe), kept for comparison.
#pragma once

#include <Eigen/Core>

#include "sim_hw/scene.h"

namespace hairrig {

struct FibreRadiance {
  Eigen::Vector3d single;   // R + TT + TRT (linear RGB), per unit irradiance of a light
  Eigen::Vector3d diffuse;  // the multiple-scattering part (shadowed more softly by the renderer)
};

// Radiance towards `to_camera` from a fibre with tangent `tangent`, lit from
// `to_light` with unit power. `albedo` is the fibre colour (0..1, linear RGB).
FibreRadiance ShadeFibre(const HairShading& shading, const Eigen::Vector3d& albedo,
                         const Eigen::Vector3d& tangent, const Eigen::Vector3d& to_light,
                         const Eigen::Vector3d& to_camera);

// The longitudinal angle (rad) at which a lobe peaks for a light and camera in
// the fibre's normal plane, as the model shifts it: R at alpha, TRT at -3/2 alpha.
double PrimaryShiftRad(const HairShading& shading);
double SecondaryShiftRad(const HairShading& shading);

}  // namespace hairrig
