#include "reconstruction/orientation_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/parallel.h"
#include "core/transform.h"

namespace hairrig {
namespace {

// The quadrature pair of Gabor kernels for strands along `direction_rad`:
// cosine (even) and sine (odd) oscillations across the strand, each zero-mean
// and scaled so that a unit sinusoid across the strand at the tuned
// wavelength gives a response of about 1.
struct GaborPair {
  cv::Mat1f even, odd;
};

GaborPair MakeGaborPair(double direction_rad, const OrientationOptions& o) {
  const int radius =
      static_cast<int>(std::ceil(3.0 * std::max(o.sigma_across_px, o.sigma_along_px)));
  const int size = 2 * radius + 1;
  GaborPair k{cv::Mat1f(size, size), cv::Mat1f(size, size)};
  const double ux = std::cos(direction_rad), uy = std::sin(direction_rad);  // along the strand
  double envelope_sum = 0;
  for (int y = -radius; y <= radius; ++y) {
    for (int x = -radius; x <= radius; ++x) {
      const double along = x * ux + y * uy, across = -x * uy + y * ux;
      const double envelope =
          std::exp(-0.5 * (across * across / (o.sigma_across_px * o.sigma_across_px) +
                           along * along / (o.sigma_along_px * o.sigma_along_px)));
      const double phase = 2 * kPi * across / o.wavelength_px;
      k.even(y + radius, x + radius) = static_cast<float>(envelope * std::cos(phase));
      k.odd(y + radius, x + radius) = static_cast<float>(envelope * std::sin(phase));
      envelope_sum += envelope;
    }
  }
  k.even -= cv::mean(k.even)[0];  // no response to flat shading
  k.odd -= cv::mean(k.odd)[0];
  k.even *= 2.0 / envelope_sum;
  k.odd *= 2.0 / envelope_sum;
  return k;
}

// Rows and columns the bank must see for the region (its bounding box grown
// by the kernels' reach over every pass), clipped to the image.
cv::Rect WorkingArea(const cv::Mat& region, cv::Size image_size, int reach) {
  cv::Rect box(0, 0, image_size.width, image_size.height);
  if (!region.empty()) {
    box = cv::boundingRect(region);
    box.x -= reach, box.y -= reach, box.width += 2 * reach, box.height += 2 * reach;
    box &= cv::Rect(0, 0, image_size.width, image_size.height);
  }
  return box;
}

// The bank's response per direction over `input`: the quadrature pair's
// energy sqrt(even^2 + odd^2), or |even|. Both kernels filter at once by the
// convolution theorem: the input's spectrum is taken once (the input extended
// by its mirror image, as cv::filter2D's BORDER_REFLECT, by at least the
// kernels' reach on every side, up to a size the DFT handles fast), and each
// direction's complex kernel even + i odd, multiplied with it and transformed
// back, gives the even response as the real part and the odd as the imaginary
// part (a correlation, as cv::filter2D: the kernel's tap at offset d sits at
// -d, wrapped). The same responses as cv::filter2D up to float rounding; each
// thread holds four complex images of the padded size while it works.
std::vector<cv::Mat1f> BankEnergy(const cv::Mat1f& input, const std::vector<GaborPair>& bank,
                                  bool quadrature, int threads) {
  const int reach = bank[0].even.rows / 2;
  const cv::Size padded(cv::getOptimalDFTSize(input.cols + 2 * reach),
                        cv::getOptimalDFTSize(input.rows + 2 * reach));
  cv::Mat1f extended;
  cv::copyMakeBorder(input, extended, reach, padded.height - input.rows - reach, reach,
                     padded.width - input.cols - reach, cv::BORDER_REFLECT);
  cv::Mat spectrum;
  cv::dft(extended, spectrum, cv::DFT_COMPLEX_OUTPUT);
  const cv::Rect inside(reach, reach, input.cols, input.rows);
  std::vector<cv::Mat1f> energy(bank.size());
  ParallelFor(bank.size(), threads, [&] {
    return [&](size_t k) {
      cv::Mat2f kernel(padded, cv::Vec2f(0, 0));
      for (int y = -reach; y <= reach; ++y) {
        for (int x = -reach; x <= reach; ++x) {
          kernel((padded.height - y) % padded.height, (padded.width - x) % padded.width) =
              cv::Vec2f(bank[k].even(y + reach, x + reach),
                        quadrature ? bank[k].odd(y + reach, x + reach) : 0.f);
        }
      }
      cv::Mat kernel_spectrum, product, response;
      cv::dft(kernel, kernel_spectrum);
      cv::mulSpectrums(spectrum, kernel_spectrum, product, 0);
      cv::idft(product, response, cv::DFT_SCALE | cv::DFT_COMPLEX_OUTPUT);
      cv::Mat1f parts[2];
      cv::split(response(inside), parts);
      if (quadrature)
        cv::magnitude(parts[0], parts[1], energy[k]);
      else
        energy[k] = cv::abs(parts[0]);
    };
  });
  return energy;
}

// One pass of the bank over `input` (already cropped): per pixel the peak
// direction, its confidence and the peak response.
OrientationMap FilterPass(const cv::Mat1f& input, const std::vector<GaborPair>& bank,
                          bool quadrature, int threads) {
  const int n = static_cast<int>(bank.size());
  const std::vector<cv::Mat1f> energy = BankEnergy(input, bank, quadrature, threads);
  OrientationMap out{cv::Mat1f(input.size()), cv::Mat1f(input.size()), cv::Mat1f(input.size())};
  const double step_deg = 180.0 / n;
  // Squared angular distance of every direction from the peak (radians^2), by offset.
  std::vector<double> distance2(static_cast<size_t>(n));
  double distance2_sum = 0;
  for (int d = 0; d < n; ++d) {
    const double deg = OrientationDifferenceDeg(0.0, d * step_deg);
    distance2[static_cast<size_t>(d)] = DegToRad(deg) * DegToRad(deg);
    distance2_sum += distance2[static_cast<size_t>(d)];
  }
  ParallelFor(static_cast<size_t>(input.rows), threads, [&] {
    return [&](size_t row) {
      const int y = static_cast<int>(row);
      for (int x = 0; x < input.cols; ++x) {
        int best = 0;
        float peak = energy[0](y, x);
        for (int k = 1; k < n; ++k) {
          if (energy[static_cast<size_t>(k)](y, x) > peak)
            peak = energy[static_cast<size_t>(k)](y, x), best = k;
        }
        // A parabola through the peak and its two neighbours (the bank is circular).
        const float before = energy[static_cast<size_t>((best + n - 1) % n)](y, x);
        const float after = energy[static_cast<size_t>((best + 1) % n)](y, x);
        const double curvature = before - 2.0 * peak + after;
        const double shift =
            curvature < 0 ? std::clamp(0.5 * (before - after) / curvature, -0.5, 0.5) : 0.0;
        double angle = (best + shift) * step_deg;
        angle = std::fmod(angle + 180.0, 180.0);
        double spread = 0;
        for (int k = 0; k < n; ++k) {
          const double drop = peak - energy[static_cast<size_t>(k)](y, x);
          spread += distance2[static_cast<size_t>((k - best + n) % n)] * drop * drop;
        }
        out.angle_deg(y, x) = static_cast<float>(angle);
        out.response(y, x) = peak;
        out.confidence(y, x) =
            peak > 1e-6f ? static_cast<float>(std::sqrt(spread / distance2_sum) / peak) : 0.0f;
      }
    };
  });
  return out;
}

// The bank over one scale of the (cropped) grey image: the shading removed by
// the difference of Gaussians, the first pass and the refinement passes.
OrientationMap FilterScale(const cv::Mat& grey, const std::vector<GaborPair>& bank,
                           const OrientationOptions& options) {
  cv::Mat1f input, coarse;
  grey.convertTo(input, CV_32F, 1.0 / 255);
  cv::GaussianBlur(input, coarse, cv::Size(), options.dog_coarse_px);
  if (options.dog_fine_px > 0) cv::GaussianBlur(input, input, cv::Size(), options.dog_fine_px);
  input -= coarse;
  OrientationMap pass = FilterPass(input, bank, options.quadrature, options.threads);
  for (int p = 0; p < options.refinement_passes; ++p) {
    // The confidence in response units (high on the fibres, where the even kernel peaks).
    const cv::Mat1f ridges(cv::Mat(pass.confidence.mul(pass.response)));
    pass = FilterPass(ridges, bank, options.quadrature, options.threads);
  }
  return pass;
}

// Directions as doubled-angle vectors (cos 2a, sin 2a), each scaled by
// `weight` (empty: 1), so that a and a + 180 deg agree and averaging them is linear.
void DoubledAngleVectors(const cv::Mat1f& angle_deg, const cv::Mat1f& weight, cv::Mat1f* c2,
                         cv::Mat1f* s2) {
  *c2 = cv::Mat1f(angle_deg.size());
  *s2 = cv::Mat1f(angle_deg.size());
  for (int y = 0; y < angle_deg.rows; ++y) {
    for (int x = 0; x < angle_deg.cols; ++x) {
      const double a = DegToRad(2.0 * angle_deg(y, x));
      const double w = weight.empty() ? 1.0 : weight(y, x);
      (*c2)(y, x) = static_cast<float>(w * std::cos(a));
      (*s2)(y, x) = static_cast<float>(w * std::sin(a));
    }
  }
}

// The direction in [0, 180) of a doubled-angle vector.
float AngleOfDoubled(float c2, float s2) {
  const double deg = 0.5 * RadToDeg(std::atan2(s2, c2));
  return static_cast<float>(deg < 0 ? deg + 180.0 : deg);
}

// `coarse` (a map of the image at a smaller size) brought to `size`: the
// direction interpolated as the doubled-angle vector, confidence and response
// bilinearly.
OrientationMap Upsampled(const OrientationMap& coarse, cv::Size size) {
  cv::Mat1f c2, s2;
  DoubledAngleVectors(coarse.angle_deg, cv::Mat1f(), &c2, &s2);
  OrientationMap out;
  cv::resize(c2, c2, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(s2, s2, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(coarse.confidence, out.confidence, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(coarse.response, out.response, size, 0, 0, cv::INTER_LINEAR);
  out.angle_deg = cv::Mat1f(size);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) out.angle_deg(y, x) = AngleOfDoubled(c2(y, x), s2(y, x));
  return out;
}

// Per pixel, the scale with the higher confidence.
void KeepMoreConfident(const OrientationMap& other, OrientationMap* best) {
  for (int y = 0; y < best->angle_deg.rows; ++y) {
    for (int x = 0; x < best->angle_deg.cols; ++x) {
      if (other.confidence(y, x) <= best->confidence(y, x)) continue;
      best->angle_deg(y, x) = other.angle_deg(y, x);
      best->confidence(y, x) = other.confidence(y, x);
      best->response(y, x) = other.response(y, x);
    }
  }
}

// The directions averaged over a Gaussian window of `sigma_px`, each weighed
// by its confidence, as doubled-angle vectors; the confidence scaled by how
// well they agree.
void SmoothDirections(double sigma_px, OrientationMap* map) {
  cv::Mat1f c2, s2, weight;
  DoubledAngleVectors(map->angle_deg, map->confidence, &c2, &s2);
  cv::GaussianBlur(c2, c2, cv::Size(), sigma_px);
  cv::GaussianBlur(s2, s2, cv::Size(), sigma_px);
  cv::GaussianBlur(map->confidence, weight, cv::Size(), sigma_px);
  for (int y = 0; y < c2.rows; ++y) {
    for (int x = 0; x < c2.cols; ++x) {
      map->angle_deg(y, x) = AngleOfDoubled(c2(y, x), s2(y, x));
      const float agreement =
          weight(y, x) > 1e-6f ? std::hypot(c2(y, x), s2(y, x)) / weight(y, x) : 0.0f;
      map->confidence(y, x) *= std::min(agreement, 1.0f);
    }
  }
}

}  // namespace

Status OrientationOptions::Check() const {
  if (directions < 4 || directions > 720)
    return InvalidArgument("orientation directions must be 4..720");
  if (!(sigma_across_px > 0) || !(sigma_along_px > 0))
    return InvalidArgument("orientation sigmas must be positive");
  if (!(wavelength_px > 1)) return InvalidArgument("orientation wavelength_px must exceed 1 pixel");
  if (!(dog_fine_px >= 0) || !(dog_coarse_px > dog_fine_px)) {
    return InvalidArgument("orientation dog_coarse_px must exceed dog_fine_px (>= 0)");
  }
  if (refinement_passes < 0 || refinement_passes > 10)
    return InvalidArgument("orientation refinement_passes must be 0..10");
  if (scales < 1 || scales > 5) return InvalidArgument("orientation scales must be 1..5");
  if (!(smoothing_px >= 0 && smoothing_px <= 50))
    return InvalidArgument("orientation smoothing_px must be 0..50");
  if (threads < 1) return InvalidArgument("orientation threads must be at least 1");
  return Status::Ok();
}

double OrientationDifferenceDeg(double a_deg, double b_deg) {
  const double d = std::fmod(std::abs(a_deg - b_deg), 180.0);
  return std::min(d, 180.0 - d);
}

Result<OrientationMap> ComputeOrientationMap(const cv::Mat& image, const cv::Mat& region,
                                             const OrientationOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  if (image.empty()) return InvalidArgument("orientation map of an empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    return InvalidArgument("orientation map needs an 8-bit grey or BGR image");
  }
  if (!region.empty() && (region.size() != image.size() || region.type() != CV_8U)) {
    return InvalidArgument("orientation region must be an 8-bit mask of the image's size");
  }
  std::vector<GaborPair> bank;
  for (int k = 0; k < options.directions; ++k)
    bank.push_back(MakeGaborPair(kPi * k / options.directions, options));
  const int kernel_reach = bank[0].even.rows / 2;
  const int coarsest = 1 << (options.scales - 1);
  const int reach = coarsest * (kernel_reach * (options.refinement_passes + 1) +
                                static_cast<int>(std::ceil(3 * options.dog_coarse_px))) +
                    static_cast<int>(std::ceil(3 * options.smoothing_px));
  const cv::Rect area = WorkingArea(region, image.size(), reach);

  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image(area), grey, cv::COLOR_BGR2GRAY);
  else
    grey = image(area);
  OrientationMap pass = FilterScale(grey, bank, options);
  cv::Mat level = grey;
  for (int scale = 1; scale < options.scales; ++scale) {
    cv::pyrDown(level, level);
    KeepMoreConfident(Upsampled(FilterScale(level, bank, options), grey.size()), &pass);
  }
  if (options.smoothing_px > 0) SmoothDirections(options.smoothing_px, &pass);

  OrientationMap out{cv::Mat1f(image.size(), std::numeric_limits<float>::quiet_NaN()),
                     cv::Mat1f(image.size(), 0.0f), cv::Mat1f(image.size(), 0.0f)};
  pass.angle_deg.copyTo(out.angle_deg(area));
  pass.confidence.copyTo(out.confidence(area));
  pass.response.copyTo(out.response(area));
  if (!region.empty()) {
    out.angle_deg.setTo(std::numeric_limits<float>::quiet_NaN(), region == 0);
    out.confidence.setTo(0.0f, region == 0);
    out.response.setTo(0.0f, region == 0);
  }
  return out;
}

cv::Mat OrientationPicture(const OrientationMap& map) {
  cv::Mat hsv(map.angle_deg.size(), CV_8UC3);
  for (int y = 0; y < hsv.rows; ++y) {
    for (int x = 0; x < hsv.cols; ++x) {
      const float angle = map.angle_deg(y, x);
      const bool known = std::isfinite(angle);
      const float c = std::clamp(map.confidence(y, x), 0.0f, 1.0f);
      hsv.at<cv::Vec3b>(y, x) =
          known ? cv::Vec3b(static_cast<uint8_t>(angle), 255, static_cast<uint8_t>(255 * c))
                : cv::Vec3b(0, 0, 0);
    }
  }
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);  // OpenCV's 8-bit hue runs 0..180: one unit per degree
  return bgr;
}

}  // namespace hairrig
