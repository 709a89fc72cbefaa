// 2D orientation maps of hair images: per pixel the direction of the strands
// seen there and how sure that is.
//
// The filter bank of Luo et al. 2013 Sec. 4 ("2D orientation maps", after Luo
// et al. 2012): each pixel is filtered with Gabor kernels at N directions
// over [0, 180); the direction is the strongest response's (refined between
// its neighbours by a parabola), the confidence comes from how the responses
// spread around that peak (Paris et al. 2004), and the map can be refined
// iteratively by filtering the previous pass's confidence with the same bank
// (Chai et al. 2012). The paper's even kernel and this module's default, the
// quadrature pair's energy, are both options, measured side by side in
// bench/orientation_bench.cpp. A difference of Gaussians removes the shading
// before the first pass. With `scales` > 1 the bank also runs on an image
// pyramid and each pixel keeps its most confident scale (per-pixel scale
// selection, as Paris et al. 2004 choose among filter parameters).
//
// Angles in degrees in [0, 180), image frame: 0 along +x, 90 along +y (down
// the image), the convention of the simulated rig's ground truth.
#pragma once

#include <opencv2/core/mat.hpp>

#include "core/status.h"

namespace hairrig {

struct OrientationOptions {
  int directions = 32;           // filters over [0, 180); >= 4
  double sigma_across_px = 1.8;  // Gabor envelope across the strand (the oscillation's axis)
  double sigma_along_px = 2.4;   // ... and along it
  double wavelength_px = 4.3;    // the oscillation's period (0.23 cycles per pixel)
  double dog_fine_px = 0.6;      // difference-of-Gaussians prefilter: fine and coarse sigma
  double dog_coarse_px = 3.0;
  // Passes over the previous pass's confidence (times its response) after the
  // first (0 = none). Chai et al. 2012 use 2-3 with the even kernel; on the
  // simulated rig's renders they raise the error (bench/orientation_bench.cpp).
  int refinement_passes = 0;
  // The response per direction: |even| (the cosine kernel alone, as Luo et al.
  // 2012) or the quadrature pair's energy sqrt(even^2 + odd^2), which does not
  // depend on where a pixel lies across a fibre (measured: median error 7.9 deg
  // instead of 12.4 deg on the default scene).
  bool quadrature = true;
  // Scales of an image pyramid the bank runs on: 1 = the image alone (Luo et
  // al.); n > 1 adds the image at 1/2, ..., 1/2^(n-1) of its size, which tunes
  // the same bank to wavelengths 2x, ..., 2^(n-1)x (hair whose flow shows at
  // the scale of wisps, not of single fibres). Each pixel takes the direction
  // of the scale where its confidence is highest; the confidence compares
  // between scales because it is the responses' spread relative to their peak.
  // The default, 3 with smoothing_px 2, holds on images unlike the simulated
  // rig's renders (a path tracer's: median error 15 deg where the image alone
  // gives 37) at a cost of under 1 % of the strands' F1 on the renders
  // (docs/accuracy.md, "On images unlike the renderer's own"); scales 1 with
  // smoothing_px 0 is Luo et al.'s filter, measurable beside it.
  int scales = 3;
  // Sigma (px) of a confidence-weighted average of the directions (as doubled-
  // angle vectors) after the bank; 0 = none. Fibre-scale glints scatter the
  // bank's answer pixel by pixel around a flow that is smooth over a wisp; the
  // average keeps the flow. The confidence is then multiplied by the
  // directions' agreement in the window (the average vector's length, 0..1).
  double smoothing_px = 2;
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct OrientationMap {
  cv::Mat1f angle_deg;  // [0, 180); NaN outside the region
  cv::Mat1f
      confidence;      // 0 (no preferred direction) .. 1 (one direction only); 0 outside the region
  cv::Mat1f response;  // the strongest filter response (same units as the filtered image)
};

// `image`: 8-bit grey or BGR. `region`: CV_8U, non-zero where the map is
// wanted (empty = everywhere); pixels outside it are still filtered for their
// neighbours. InvalidArgument for an empty image, a region of another size or
// bad options.
Result<OrientationMap> ComputeOrientationMap(const cv::Mat& image, const cv::Mat& region,
                                             const OrientationOptions& options);

// A picture of a map a person reads: hue = angle (red 0, green 60, blue 120
// deg), brightness = confidence; black outside the region. CV_8UC3 (BGR).
cv::Mat OrientationPicture(const OrientationMap& map);

// The unsigned difference of two directions in degrees: 0..90.
double OrientationDifferenceDeg(double a_deg, double b_deg);

}  // namespace hairrig
