#include "sim_hw/render_support.h"

#include <algorithm>
#include <cmath>

namespace hairrig {
namespace render_support {

cv::Mat ExposeRadiance(const cv::Mat3f& radiance, const SceneCamera& camera, double exposure_s,
                       double gain_db, bool noise, uint64_t noise_seed) {
  const CameraPipeline& pipeline = camera.pipeline;
  const double exposure = exposure_s > 0 ? exposure_s : camera.exposure_s;
  const float scale =
      static_cast<float>(255.0 * exposure * camera.sensitivity * std::pow(10.0, gain_db / 20.0) *
                         std::exp2(pipeline.exposure_ev));
  const float read = static_cast<float>(camera.read_noise_dn);
  const float shot = static_cast<float>(camera.shot_noise_gain * pipeline.ShotVarianceScale());
  NoiseSource source(noise_seed);
  NoiseSource grain_source(~noise_seed);
  const float grain_sd = noise ? static_cast<float>(pipeline.render_grain_sd) : 0.0f;
  // Linear DN per photosite: every channel, or the one its colour filter passes.
  cv::Mat3f sensor_dn(radiance.rows, radiance.cols, cv::Vec3f(0, 0, 0));
  for (int y = 0; y < radiance.rows; ++y) {
    const cv::Vec3f* in = radiance.ptr<cv::Vec3f>(y);
    cv::Vec3f* out = sensor_dn.ptr<cv::Vec3f>(y);
    for (int x = 0; x < radiance.cols; ++x) {
      const int first = pipeline.bayer ? BayerChannel(x, y) : 0;
      const int last = pipeline.bayer ? first + 1 : 3;
      const float grain =
          grain_sd > 0 ? std::exp(grain_sd * grain_source.Next() - 0.5f * grain_sd * grain_sd)
                       : 1.0f;
      for (int c = first; c < last; ++c) {
        float dn = in[x][c] * scale * grain;
        if (noise) dn += source.Next() * std::sqrt(read * read + shot * std::max(dn, 0.0f));
        out[x][c] = std::clamp(dn, 0.0f, 255.0f);
      }
    }
  }
  return DevelopImage(sensor_dn, pipeline);
}

}  // namespace render_support
}  // namespace hairrig
