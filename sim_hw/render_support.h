// Pieces every renderer of the simulated rig shares (sim_hw/renderer.cpp for
// the scene, sim_hw/charuco_views.cpp for a ChArUco board): rays through the
// inverse of the lens model, a per-pixel hash for stratified edge samples and
// reproducible sensor noise. Internal to sim_hw.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"
#include "sim_hw/scene.h"

namespace hairrig {
namespace render_support {

constexpr int kEdgeSamples = 8;  // per axis, for pixels on an edge of a printed pattern

// Normalised ray (x, y) for any pixel position, interpolated in a grid of exact
// inverse-distortion solutions (spacing 4 px; interpolation error < 1e-4 px).
class RayTable {
 public:
  static Result<RayTable> Build(const CameraIntrinsics& camera) {
    RayTable t;
    t.cols_ = static_cast<int>(camera.width_px / kStep) + 4;
    t.rows_ = static_cast<int>(camera.height_px / kStep) + 4;
    t.rays_.resize(static_cast<size_t>(t.cols_ * t.rows_));
    for (int r = 0; r < t.rows_; ++r) {
      for (int c = 0; c < t.cols_; ++c) {
        const Eigen::Vector2d uv(kOrigin + c * kStep, kOrigin + r * kStep);
        auto xy = UndistortPixel(camera, uv);
        if (!xy.ok()) return xy.status().WithContext("camera lens model over the image");
        t.rays_[static_cast<size_t>(r * t.cols_ + c)] = *xy;
      }
    }
    return t;
  }
  Eigen::Vector3d Ray(double u, double v) const {
    const double gx = std::clamp((u - kOrigin) / kStep, 0.0, cols_ - 1.001);
    const double gy = std::clamp((v - kOrigin) / kStep, 0.0, rows_ - 1.001);
    const int c = static_cast<int>(gx), r = static_cast<int>(gy);
    const double fx = gx - c, fy = gy - r;
    const auto at = [&](int rr, int cc) -> const Eigen::Vector2d& {
      return rays_[static_cast<size_t>(rr * cols_ + cc)];
    };
    const Eigen::Vector2d xy = (1 - fy) * ((1 - fx) * at(r, c) + fx * at(r, c + 1)) +
                               fy * ((1 - fx) * at(r + 1, c) + fx * at(r + 1, c + 1));
    return {xy.x(), xy.y(), 1.0};
  }

 private:
  static constexpr double kStep = 4.0;
  static constexpr double kOrigin = -6.0;
  int cols_ = 0, rows_ = 0;
  std::vector<Eigen::Vector2d> rays_;
};

inline uint32_t HashPixel(int x, int y, uint32_t salt) {
  uint32_t h = static_cast<uint32_t>(x) * 0x9E3779B1u ^
               (static_cast<uint32_t>(y) + 0x7F4A7C15u) * 0x85EBCA77u ^ salt;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}

// A 64-bit hash of `x` whose every bit depends on every bit of `x` (the
// finaliser of splitmix64): seeds for NoiseSource from structured indices.
inline uint64_t MixBits(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Fast reproducible standard normal samples (xorshift + a precomputed table).
class NoiseSource {
 public:
  explicit NoiseSource(uint64_t seed)
      : state_(seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull) {
    if (state_ == 0) state_ = 1;
  }
  float Next() {
    state_ ^= state_ << 13;
    state_ ^= state_ >> 7;
    state_ ^= state_ << 17;
    return Table()[state_ & (kSize - 1)];
  }

 private:
  static constexpr size_t kSize = 1 << 16;
  static const std::vector<float>& Table() {
    static const std::vector<float> table = [] {
      // Inverse CDF at stratified probabilities: an exact N(0,1) sample set.
      std::vector<float> t(kSize);
      for (size_t i = 0; i < kSize; ++i) {
        const double p = (static_cast<double>(i) + 0.5) / kSize;
        double x = std::sqrt(2.0) * InverseErf(2.0 * p - 1.0);
        t[i] = static_cast<float>(x);
      }
      // Shuffle deterministically so consecutive states are uncorrelated.
      uint64_t s = 88172645463325252ull;
      for (size_t i = kSize - 1; i > 0; --i) {
        s ^= s << 13, s ^= s >> 7, s ^= s << 17;
        std::swap(t[i], t[s % (i + 1)]);
      }
      return t;
    }();
    return table;
  }
  static double InverseErf(double y) {
    // Winitzki's closed-form approximation, then Newton steps on erf(x) - y.
    double x = 0.0;
    const double a = 0.147;
    const double ln = std::log(1.0 - y * y);
    const double term = 2.0 / (kPi * a) + ln / 2.0;
    x = std::copysign(std::sqrt(std::sqrt(term * term - ln / a) - term), y);
    for (int i = 0; i < 3; ++i) x -= (std::erf(x) - y) / (2.0 / std::sqrt(kPi) * std::exp(-x * x));
    return x;
  }
  uint64_t state_;
};

// The 8-bit BGR image a camera records of `radiance` (linear, BGR, on the
// sensor: defocus already applied): exposure (s; 0 = the camera's nominal),
// gain (dB) and the pipeline's exposure error scale it, then read and shot
// noise as the scene camera states at the pipeline's ISO, reproducible from
// `noise_seed`, then the camera's processing (sim_hw/camera_pipeline.h).
cv::Mat ExposeRadiance(const cv::Mat3f& radiance, const SceneCamera& camera, double exposure_s,
                       double gain_db, bool noise, uint64_t noise_seed);

}  // namespace render_support
}  // namespace hairrig
