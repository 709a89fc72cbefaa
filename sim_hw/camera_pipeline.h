// What a real camera does to the light between the scene and the file it
// writes, for the simulated rig: the lens' depth of field, the sensor's noise
// at an ISO, its colour filter array and the demosaicing that fills it in, the
// white balance and exposure a camera gets wrong, its tone curve and its JPEG.
// Each is off by default (the image is the scene's linear radiance, exposed,
// with the camera's own noise), so a scene states only what it changes
// (`camera_pipeline:` in etc/scenes/*.yaml, sim_hw/scene.h).
//
// Order of operations, as in a camera: optics (defocus, on linear radiance,
// DefocusRadiance) -> sensor (exposure x 2^exposure_ev, one colour per
// photosite with a Bayer mosaic, shot and read noise at the ISO, saturation at
// 255 DN) -> processing (bilinear demosaicing, white balance gains, tone curve,
// 8-bit quantisation, JPEG encoding and decoding).
#pragma once

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "core/status.h"

namespace hairrig {

struct CameraPipeline {
  // Noise: the camera's read and shot noise are stated at ISO 100. At ISO n
  // the exposure is shortened and the signal amplified by g = n / 100 (the
  // image is as bright): the shot noise's variance grows by g (g times fewer
  // photons per DN). The read noise stays: in 8-bit DN it is the converter's
  // and the amplifier's after the gain (a sensor's input-referred read noise,
  // a few electrons, is far below one 8-bit DN at any ISO).
  double iso = 100;
  double exposure_ev = 0;                  // exposure error in stops (+1: twice the light)
  Eigen::Vector3d white_balance{1, 1, 1};  // gains on linear R, G, B after demosaicing
  bool bayer = false;                      // RGGB mosaic, bilinear demosaicing
  enum class Tone { kLinear, kSrgb };
  Tone tone = Tone::kLinear;  // kSrgb: the sRGB curve of a camera's JPEG
  int jpeg_quality = 0;       // 0: none; 1..100: encoded and decoded at it
  // Depth of field of a thin lens: 0 = pinhole (everything sharp). The lens'
  // focal length is fx_px x pixel_um; the circle of confusion of a point at
  // depth z when focused at s is (f / N) (f / (s - f)) |z - s| / z on the
  // sensor. pixel_um is the pitch of the image's pixels on the sensor: a
  // DSLR's 4 um photosites written at a quarter of their count are 16 um.
  double f_number = 0;
  double focus_mm = 0;  // distance in focus along the optical axis; 0 = the camera's target
  double pixel_um = 16;
  double lens_blur_px = 0;  // Gaussian sigma of a soft lens, everywhere in the image
  // Not a camera's: the Monte Carlo grain of a path tracer's image at few
  // samples per pixel, which images from another renderer carry. Each pixel's
  // radiance (its channels alike) is multiplied by a log-normal factor of mean
  // 1 and this sd of its log, independent per pixel, before the sensor (with
  // the noise: off where a render asks for none). 0 = none.
  double render_grain_sd = 0;

  bool Identity() const;
  // InvalidArgument naming the field (camera_pipeline.iso, ...): a value out
  // of range or not finite.
  Status Check() const;
  // The shot noise's variance at the ISO over its variance at ISO 100.
  double ShotVarianceScale() const { return iso / 100.0; }
};

// The circle of confusion's diameter in pixels at depth `z_mm` for a camera of
// focal length `focal_px` focused at `focus_mm` (0 when f_number is 0).
double CircleOfConfusionPx(const CameraPipeline& pipeline, double focal_px, double focus_mm,
                           double z_mm);

// The optical image on the sensor: each pixel of `radiance` (linear) blurred
// by a Gaussian of sigma = half its circle of confusion at `depth_mm` (the
// nearest surface; infinite where the backdrop is) and lens_blur_px, gathered
// from a stack of blurred images (depth discontinuities are not modelled: a
// blurred foreground does not spread over a sharp background). Returns
// `radiance` itself when the pipeline has neither.
cv::Mat3f DefocusRadiance(const cv::Mat3f& radiance, const cv::Mat1f& depth_mm,
                          const CameraPipeline& pipeline, double focal_px, double focus_mm);

// The processing after the sensor: `sensor_dn` (linear DN, BGR or one
// channel per photosite with `bayer`, already noisy, clipped to 0..255)
// demosaiced, white balanced, tone mapped, quantised and JPEG'd: CV_8UC3 BGR.
cv::Mat DevelopImage(const cv::Mat3f& sensor_dn, const CameraPipeline& pipeline);

// Which channel (0 = B, 1 = G, 2 = R) the RGGB mosaic samples at (x, y).
inline int BayerChannel(int x, int y) {
  if ((y & 1) == 0) return (x & 1) == 0 ? 2 : 1;
  return (x & 1) == 0 ? 1 : 0;
}

}  // namespace hairrig
