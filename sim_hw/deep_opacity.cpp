#include "sim_hw/deep_opacity.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hairrig {
namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

// Box blur of one texel's neighbourhood for every layer (3 x 3), in place via a copy.
void BlurLayers(std::vector<float>& opacity, int res, int layers) {
  const std::vector<float> source = opacity;
  for (int y = 0; y < res; ++y) {
    for (int x = 0; x < res; ++x) {
      for (int k = 0; k < layers; ++k) {
        float sum = 0;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= res || yy >= res) continue;
            sum += source[(static_cast<size_t>(yy) * res + xx) * layers + k];
            ++n;
          }
        }
        opacity[(static_cast<size_t>(y) * res + x) * layers + k] = sum / static_cast<float>(n);
      }
    }
  }
}

}  // namespace

bool LightShadowMap::ToTexel(const Eigen::Vector3d& p, double* u, double* v, double* depth) const {
  const Eigen::Vector3d q = light_from_frame_ * (p - light_mm_);
  if (q.z() <= 1.0) return false;
  *u = focal_ * q.x() / q.z() + 0.5 * res_;
  *v = focal_ * q.y() / q.z() + 0.5 * res_;
  *depth = q.norm();
  return *u >= 0 && *v >= 0 && *u < res_ - 1 && *v < res_ - 1;
}

Status ShadowMapOptions::Check() const {
  if (resolution < 1 || resolution > 8192)
    return InvalidArgument("resolution must lie in 1..8192, got " + std::to_string(resolution));
  if (head_resolution < 1 || head_resolution > 16384) {
    return InvalidArgument("head_resolution must lie in 1..16384, got " +
                           std::to_string(head_resolution));
  }
  if (layers < 1 || layers > 1024)
    return InvalidArgument("layers must lie in 1..1024, got " + std::to_string(layers));
  if (!(layer_mm > 0) || !std::isfinite(layer_mm))
    return InvalidArgument("layer_mm must be finite and positive");
  if (!(fibre_opacity >= 0) || !std::isfinite(fibre_opacity))
    return InvalidArgument("fibre_opacity must be finite and 0 or more");
  return Status::Ok();
}

LightShadowMap LightShadowMap::Build(const Eigen::Vector3d& light_mm,
                                     const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<size_t>& offsets, double fibre_diameter_mm,
                                     const TriangleMesh& head, const ShadowMapOptions& o) {
  LightShadowMap m;
  m.light_mm_ = light_mm;
  m.res_ = o.resolution;
  m.head_scale_ = std::max(
      1, static_cast<int>(std::lround(static_cast<double>(o.head_resolution) / o.resolution)));
  m.head_res_ = m.res_ * m.head_scale_;
  m.layers_ = o.layers;
  m.layer_mm_ = o.layer_mm;
  // Look at the centre of everything that casts or receives shadows.
  Eigen::Vector3d lo = head.MinCorner(), hi = head.MaxCorner();
  for (const auto& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector3d forward = (0.5 * (lo + hi) - light_mm).normalized();
  const Eigen::Vector3d right = forward.unitOrthogonal();
  m.light_from_frame_.row(0) = right;
  m.light_from_frame_.row(1) = forward.cross(right);
  m.light_from_frame_.row(2) = forward;
  double extent = 1e-6;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(),
                                 (c & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d q = m.light_from_frame_ * (corner - light_mm);
    if (q.z() > 1.0) extent = std::max(extent, std::max(std::abs(q.x()), std::abs(q.y())) / q.z());
  }
  m.focal_ = 0.5 * (m.res_ - 2) / extent;
  const size_t texels = static_cast<size_t>(m.res_) * m.res_;
  m.first_hair_mm_.assign(texels, kFar);
  m.head_depth_mm_.assign(static_cast<size_t>(m.head_res_) * m.head_res_, kFar);
  m.opacity_.assign(texels * static_cast<size_t>(m.layers_), 0.0f);
  // The head's depth: its triangles rasterised into the map.
  for (size_t t = 0; t < head.num_triangles(); ++t) {
    double u[3], v[3], d[3];
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      inside = m.ToTexel(head.Corner(t, k), &u[k], &v[k], &d[k]) && inside;
      u[k] *= m.head_scale_, v[k] *= m.head_scale_;
    }
    if (!inside) continue;
    const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (std::abs(area) < 1e-12) continue;
    const int x0 = static_cast<int>(std::floor(std::min({u[0], u[1], u[2]})));
    const int x1 = static_cast<int>(std::ceil(std::max({u[0], u[1], u[2]})));
    const int y0 = static_cast<int>(std::floor(std::min({v[0], v[1], v[2]})));
    const int y1 = static_cast<int>(std::ceil(std::max({v[0], v[1], v[2]})));
    for (int y = std::max(0, y0); y <= std::min(m.head_res_ - 1, y1); ++y) {
      for (int x = std::max(0, x0); x <= std::min(m.head_res_ - 1, x1); ++x) {
        const double w1 = ((x - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (y - v[0])) / area;
        const double w2 = ((u[1] - u[0]) * (y - v[0]) - (x - u[0]) * (v[1] - v[0])) / area;
        const double w0 = 1 - w1 - w2;
        if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
        float& depth = m.head_depth_mm_[static_cast<size_t>(y) * m.head_res_ + x];
        depth = std::min(depth, static_cast<float>(w0 * d[0] + w1 * d[1] + w2 * d[2]));
      }
    }
  }
  // Samples along every segment, about one per texel they cross.
  const auto for_each_sample = [&](auto&& visit) {
    for (size_t s = 0; s + 1 < offsets.size(); ++s) {
      for (size_t i = offsets[s] + 1; i < offsets[s + 1]; ++i) {
        double ua, va, da, ub, vb, db;
        if (!m.ToTexel(points[i - 1], &ua, &va, &da) || !m.ToTexel(points[i], &ub, &vb, &db))
          continue;
        const int n = 1 + static_cast<int>(std::max(std::abs(ub - ua), std::abs(vb - va)));
        const double length = (points[i] - points[i - 1]).norm() / n;
        for (int k = 0; k < n; ++k) {
          const double f = (k + 0.5) / n;
          visit(ua + f * (ub - ua), va + f * (vb - va), da + f * (db - da), length);
        }
      }
    }
  };
  for_each_sample([&](double u, double v, double d, double) {
    float& first = m.first_hair_mm_[static_cast<size_t>(v) * m.res_ + static_cast<int>(u)];
    first = std::min(first, static_cast<float>(d));
  });
  // The first hair of a texel's neighbours starts its layers too (the map is blurred below).
  {
    const std::vector<float> first = m.first_hair_mm_;
    for (int y = 1; y + 1 < m.res_; ++y)
      for (int x = 1; x + 1 < m.res_; ++x)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            m.first_hair_mm_[static_cast<size_t>(y) * m.res_ + x] =
                std::min(m.first_hair_mm_[static_cast<size_t>(y) * m.res_ + x],
                         first[static_cast<size_t>(y + dy) * m.res_ + x + dx]);
  }
  for_each_sample([&](double u, double v, double d, double length) {
    const int x = static_cast<int>(u), y = static_cast<int>(v);
    const double first = m.first_hair_mm_[static_cast<size_t>(y) * m.res_ + x];
    const int layer = std::clamp(static_cast<int>((d - first) / m.layer_mm_), 0, m.layers_ - 1);
    const double texel_mm = d / m.focal_;
    m.Layer(x, y, layer) +=
        static_cast<float>(o.fibre_opacity * fibre_diameter_mm * length / (texel_mm * texel_mm));
  });
  // Accumulate front to back: a layer holds the optical depth up to its far side.
  for (size_t t = 0; t < texels; ++t) {
    for (int k = 1; k < m.layers_; ++k)
      m.opacity_[t * m.layers_ + k] += m.opacity_[t * m.layers_ + k - 1];
  }
  BlurLayers(m.opacity_, m.res_, m.layers_);
  return m;
}

double LightShadowMap::HeadVisibility(const Eigen::Vector3d& p) const {
  double u, v, d;
  return ToTexel(p, &u, &v, &d) ? HeadVisibilityAtTexel(u, v, d) : 1.0;
}

LightShadowMap::Visibility LightShadowMap::VisibilityAt(
    const Eigen::Vector3d& p, const Eigen::Vector3d* surface_normal) const {
  double u, v, d;
  if (!ToTexel(p, &u, &v, &d)) return {};
  Visibility out{HairTransmittanceAtTexel(u, v, d), 1.0};
  if (surface_normal == nullptr) {
    out.head_visibility = HeadVisibilityAtTexel(u, v, d);
  } else {
    const double head_texel_mm = d / (focal_ * head_scale_);
    out.head_visibility = HeadVisibility(p + 1.5 * head_texel_mm * *surface_normal);
  }
  return out;
}

double LightShadowMap::HairTransmittanceAtTexel(double u, double v, double d) const {
  u -= 0.5, v -= 0.5;
  const int x = std::clamp(static_cast<int>(std::floor(u)), 0, res_ - 2);
  const int y = std::clamp(static_cast<int>(std::floor(v)), 0, res_ - 2);
  const double fx = std::clamp(u - x, 0.0, 1.0), fy = std::clamp(v - y, 0.0, 1.0);
  double depth = 0;
  for (int dy = 0; dy <= 1; ++dy) {
    for (int dx = 0; dx <= 1; ++dx) {
      const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
      const float first = first_hair_mm_[static_cast<size_t>(y + dy) * res_ + x + dx];
      if (!(first < kFar)) continue;
      // Optical depth in front of p: the layers before p's, and a share of its own.
      const double layer = (d - first) / layer_mm_ - 0.5;
      if (layer < 0) continue;
      const int k = std::min(static_cast<int>(layer), layers_ - 1);
      const double f = std::min(1.0, layer - k);
      const double before = k > 0 ? LayerAt(x + dx, y + dy, k - 1) : 0.0;
      const double after = LayerAt(x + dx, y + dy, std::min(k, layers_ - 1));
      depth += w * (k >= layers_ - 1 ? after : before + f * (after - before));
    }
  }
  return std::exp(-depth);
}

double LightShadowMap::HeadVisibilityAtTexel(double u, double v, double d) const {
  u *= head_scale_, v *= head_scale_;
  // Percentage-closer filtering over 3 x 3 texels; the bias covers the map's texel size.
  const double bias_mm = 2.0 + 1.5 * d / (focal_ * head_scale_);
  int lit = 0, n = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int x = std::clamp(static_cast<int>(u) + dx, 0, head_res_ - 1);
      const int y = std::clamp(static_cast<int>(v) + dy, 0, head_res_ - 1);
      lit += d <= head_depth_mm_[static_cast<size_t>(y) * head_res_ + x] + bias_mm ? 1 : 0;
      ++n;
    }
  }
  return static_cast<double>(lit) / n;
}

}  // namespace hairrig
