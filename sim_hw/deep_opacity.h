// Shadows cast by one point light (an LED panel) over the hair and the head:
// a deep opacity map (Yuksel & Keyser 2008, "Deep opacity maps": opacity
// layers that start at the first hair the light sees in each texel, after Kim
// & Neumann 2001's opacity shadow maps) for the hair's self-shadowing and its
// shadow on the head, and a depth map of the head for the head's shadow on
// hair and on itself. Built per rendered view (the wig turns with the
// turntable while the panels stay put). Everything is in one frame (the
// renderer uses the camera frame), millimetres.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "core/triangle_mesh.h"

namespace hairrig {

struct ShadowMapOptions {
  int resolution = 512;  // texels per side of the hair's opacity layers
  int head_resolution =
      512;  // texels per side of the head's depth map (rounded to a multiple of `resolution`)
  int layers = 16;        // opacity layers behind the first hair
  double layer_mm = 4.0;  // depth of one layer
  // A fibre's projected area times this is its optical depth; below 1 because
  // a fibre lets part of the light through (its TT lobe).
  double fibre_opacity = 0.7;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

class LightShadowMap {
 public:
  // `points` and `offsets` describe the strands (StrandSet::Offsets()),
  // `head` a closed mesh; all in the frame of `light_mm`.
  static LightShadowMap Build(const Eigen::Vector3d& light_mm,
                              const std::vector<Eigen::Vector3d>& points,
                              const std::vector<size_t>& offsets, double fibre_diameter_mm,
                              const TriangleMesh& head, const ShadowMapOptions& options = {});

  // Whether the head hides p (0 hidden, 1 lit, soft on the edge).
  double HeadVisibility(const Eigen::Vector3d& p) const;
  // The fraction of the light's direct radiance that reaches p through the
  // hair (0..1) and the head's visibility, at once (one projection into the map). For a point on
  // the head, pass its outward normal: the head's depth is then read a texel and a half off the
  // surface (normal-offset shadow mapping), so that the head does not shadow itself in stripes
  // where it turns from the light.
  struct Visibility {
    double hair_transmittance = 1;
    double head_visibility = 1;
  };
  Visibility VisibilityAt(const Eigen::Vector3d& p,
                          const Eigen::Vector3d* surface_normal = nullptr) const;

 private:
  bool ToTexel(const Eigen::Vector3d& p, double* u, double* v, double* depth) const;
  double HairTransmittanceAtTexel(double u, double v, double depth) const;
  double HeadVisibilityAtTexel(double u, double v, double depth) const;
  float& Layer(int x, int y, int k) {
    return opacity_[(static_cast<size_t>(y) * res_ + x) * layers_ + k];
  }
  float LayerAt(int x, int y, int k) const {
    return opacity_[(static_cast<size_t>(y) * res_ + x) * layers_ + k];
  }

  Eigen::Matrix3d light_from_frame_;  // rotation; +z along the light's view
  Eigen::Vector3d light_mm_;
  double focal_ = 1;  // texels per unit of x/z
  int res_ = 0, layers_ = 0;
  int head_scale_ = 1;  // head map texels per opacity texel, per side
  int head_res_ = 0;
  double layer_mm_ = 4;
  std::vector<float> first_hair_mm_;  // per texel: depth of the first hair (inf: none)
  std::vector<float> head_depth_mm_;  // per head texel: depth of the head (inf: none)
  std::vector<float>
      opacity_;  // per texel and layer: optical depth accumulated up to the layer's far side
};

}  // namespace hairrig
