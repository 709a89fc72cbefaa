#include "sim_hw/render_support.h"

#include <algorithm>

namespace hairrig {
namespace render_support {

cv::Mat ExposeRadiance(const cv::Mat3f& radiance, const SceneCamera& camera, double exposure_s,
                       double gain_db, bool noise, uint64_t noise_seed) {
  const double exposure = exposure_s > 0 ? exposure_s : camera.exposure_s;
  const float scale =
      static_cast<float>(255.0 * exposure * camera.sensitivity * std::pow(10.0, gain_db / 20.0));
  const float read = static_cast<float>(camera.read_noise_dn);
  const float shot = static_cast<float>(camera.shot_noise_gain);
  NoiseSource source(noise_seed);
  cv::Mat image(radiance.rows, radiance.cols, CV_8UC3);
  for (int y = 0; y < radiance.rows; ++y) {
    const cv::Vec3f* in = radiance.ptr<cv::Vec3f>(y);
    cv::Vec3b* out = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < radiance.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        float dn = in[x][c] * scale;
        if (noise) dn += source.Next() * std::sqrt(read * read + shot * std::max(dn, 0.0f));
        out[x][c] = static_cast<uint8_t>(std::clamp(std::lround(dn), 0L, 255L));
      }
    }
  }
  return image;
}

}  // namespace render_support
}  // namespace hairrig
