#include "reconstruction/hair_segmentation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "core/statistics.h"
#include "reconstruction/gaussian_mixture.h"

namespace hairrig {
namespace {

// A comparison's or a logical operation's result as an 8-bit mask.
cv::Mat1b Mask(const cv::MatExpr& expression) {
  const cv::Mat m = expression;
  return m;
}

// The backdrop as a Gaussian in BGR, from the image's border band.
struct BackdropModel {
  cv::Vec3d mean;
  cv::Matx33d inverse_covariance;
  cv::Vec3d channel_sigma;  // standard deviation of each channel
  double sigma = 0;         // mean standard deviation of the channels
};

Result<BackdropModel> FitBackdrop(const cv::Mat3b& bgr, int border) {
  cv::Mat1b band(bgr.size(), uint8_t{255});
  band(cv::Rect(border, border, bgr.cols - 2 * border, bgr.rows - 2 * border)).setTo(0);
  std::vector<cv::Vec3d> samples;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      if (band(y, x)) samples.push_back(cv::Vec3d(bgr(y, x)[0], bgr(y, x)[1], bgr(y, x)[2]));
    }
  }
  BackdropModel model;
  cv::Vec3d sum(0, 0, 0);
  for (const cv::Vec3d& s : samples) sum += s;
  model.mean = sum / static_cast<double>(samples.size());
  cv::Matx33d cov = cv::Matx33d::zeros();
  for (const cv::Vec3d& s : samples) {
    const cv::Vec3d d = s - model.mean;
    cov += d * d.t();
  }
  cov *= 1.0 / static_cast<double>(samples.size());
  model.sigma = std::sqrt((cov(0, 0) + cov(1, 1) + cov(2, 2)) / 3.0);
  model.channel_sigma = cv::Vec3d(std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2)));
  if (model.sigma > 30.0) {
    return FailedPrecondition("the image's border is not a plain backdrop (its colour varies by " +
                              std::to_string(static_cast<int>(model.sigma)) +
                              " grey levels): keep the subject and the box off the frame's edges");
  }
  // A floor of 1.5 grey levels keeps the inverse finite for a clean or grey
  // backdrop (a grey image has three equal channels).
  cov += cv::Matx33d::eye() * (1.5 * 1.5);
  model.inverse_covariance = cov.inv();
  return model;
}

cv::Mat1f BackdropDistance(const cv::Mat3b& bgr, const BackdropModel& model) {
  cv::Mat1f distance(bgr.size());
  distance.forEach([&](float& d, const int* pos) {
    const cv::Vec3b& p = bgr(pos[0], pos[1]);
    const cv::Vec3d v(p[0] - model.mean[0], p[1] - model.mean[1], p[2] - model.mean[2]);
    d = static_cast<float>(std::sqrt(std::max(0.0, (v.t() * model.inverse_covariance * v)(0))));
  });
  return distance;
}

// The least share of the backdrop's light that pixel `p` must hide: no
// colour is negative, so a pixel darker than the backdrop in a channel covers
// at least 1 - p / backdrop of it, whatever covers it. Each channel is taken
// 3 of the backdrop's standard deviations brighter (its noise); the largest
// share over the channels, 0 when the pixel is nowhere darker. A blend of
// hair over the backdrop never exceeds its true coverage here.
double HiddenBackdropShare(const cv::Vec3b& p, const BackdropModel& backdrop) {
  constexpr double kNoiseSigmas = 3.0;
  double share = 0;
  for (int c = 0; c < 3; ++c) {
    if (backdrop.mean[c] < 1.0) continue;
    share =
        std::max(share, 1.0 - (p[c] + kNoiseSigmas * backdrop.channel_sigma[c]) / backdrop.mean[c]);
  }
  return share;
}

// The pieces (8-connected) of `mask` that come within `reach_px` (a square
// window) of a pixel of `reference`.
cv::Mat1b PiecesTouching(const cv::Mat1b& mask, const cv::Mat1b& reference, int reach_px) {
  cv::Mat1b near;
  cv::dilate(
      reference, near,
      cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach_px + 1, 2 * reach_px + 1)));
  cv::Mat1i pieces;
  const int n = cv::connectedComponents(mask, pieces, 8, CV_32S);
  std::vector<uint8_t> touches(static_cast<size_t>(n), 0);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x)
      if (mask(y, x) && near(y, x)) touches[static_cast<size_t>(pieces(y, x))] = 255;
  touches[0] = 0;
  cv::Mat1b out(mask.size(), uint8_t{0});
  out.forEach([&](uint8_t& o, const int* pos) {
    o = touches[static_cast<size_t>(pieces(pos[0], pos[1]))];
  });
  return out;
}

// The pixels outside `foreground` connected (8-way) to the image's border:
// the backdrop around the subject, not the gaps within it. A region outside
// `foreground` that is not backdrop (the calibration box) counts as outside.
cv::Mat1b OuterBackdrop(const cv::Mat1b& foreground) {
  const cv::Mat1b outside = Mask(foreground == 0);
  cv::Mat1b border(outside.size(), uint8_t{0});
  cv::rectangle(border, cv::Rect(0, 0, border.cols, border.rows), cv::Scalar(255), 1);
  return PiecesTouching(outside, Mask(border & outside), 0);
}

// The pixels of the hair's region (`hair_region`) that are skin in the hair's
// shadow: their coverage (`distance` / `full_coverage`) is under 0.5, yet they
// hide at least half of the backdrop's light in some channel
// (HiddenBackdropShare), so they are opaque and darker than the hair. With
// `touching_only`, only their pieces that touch the skin the material model
// found (`skin`, within 3 px): skin in shadow continues lit skin (the neck
// under the jaw); the dark gaps between locks, as opaque and as dark, lie
// within the hair.
cv::Mat1b OpaqueShadowOnSkin(const cv::Mat3b& bgr, const cv::Mat1b& hair_region,
                             const cv::Mat1f& distance, float full_coverage,
                             const BackdropModel& backdrop, const cv::Mat1b& skin,
                             bool touching_only) {
  cv::Mat1b opaque(bgr.size(), uint8_t{0});
  opaque.forEach([&](uint8_t& o, const int* pos) {
    const int y = pos[0], x = pos[1];
    if (hair_region(y, x) && distance(y, x) < 0.5f * full_coverage &&
        HiddenBackdropShare(bgr(y, x), backdrop) >= 0.5)
      o = 255;
  });
  if (!touching_only) return opaque;
  return PiecesTouching(opaque, skin, 3);
}

// Gaussian blurs of values over the pixels in `weights` only (normalised
// convolution): pixels outside take no part, so no step at the foreground's
// outline enters the result. The weights' own blur is made once per sigma.
class BlurWithin {
 public:
  explicit BlurWithin(cv::Mat1f weights) : weights_(std::move(weights)) {}

  cv::Mat1f operator()(const cv::Mat1f& values, double sigma) {
    cv::Mat1f product, weighted, blurred;
    cv::multiply(values, weights_, product);
    cv::GaussianBlur(product, weighted, cv::Size(), sigma);
    cv::divide(weighted, Blurred(sigma).norm, blurred);
    return blurred;
  }

  // The weights blurred with `sigma` (not clamped).
  const cv::Mat1f& Weight(double sigma) { return Blurred(sigma).weight; }

 private:
  struct BlurredWeights {
    double sigma;
    cv::Mat1f weight, norm;  // norm: the weight clamped to at least 1e-3
  };

  const BlurredWeights& Blurred(double sigma) {
    for (const BlurredWeights& b : blurred_)
      if (b.sigma == sigma) return b;
    BlurredWeights b{sigma, {}, {}};
    cv::GaussianBlur(weights_, b.weight, cv::Size(), sigma);
    cv::max(b.weight, 1e-3, b.norm);
    blurred_.push_back(std::move(b));
    return blurred_.back();
  }

  cv::Mat1f weights_;
  std::deque<BlurredWeights> blurred_;
};

// How far (px) OpenCV's Gaussian kernel of `sigma` reaches on float images.
int GaussianReach(double sigma) { return cvRound(sigma * 8 + 1) / 2; }

// The texture band within `within` (a band-pass of one image plane, blurred
// within the mask so that the step at its outline does not count), squared
// and averaged over a window of `sigma`, relative to the squared local
// brightness (+ 8 grey levels), so that hair in shadow stays textured. Every
// blur takes only pixels in `within`, so the result is 0 further than the
// blurs reach from it: it is computed on the mask's bounding box grown by
// that reach (the values over the whole image, up to float rounding).
cv::Mat1f RelativeBandEnergy(const cv::Mat1b& plane, const cv::Mat1b& within, double sigma) {
  constexpr double kFine = 1.5, kCoarse = 4.0;
  cv::Mat1f out(plane.size(), 0.f);
  const cv::Rect box = cv::boundingRect(within);
  if (box.empty()) return out;
  const int reach = GaussianReach(std::max({kFine, kCoarse, sigma})) + 1;
  const cv::Rect area =
      cv::Rect(box.x - reach, box.y - reach, box.width + 2 * reach, box.height + 2 * reach) &
      cv::Rect(0, 0, plane.cols, plane.rows);
  cv::Mat1f grey, weights;
  plane(area).convertTo(grey, CV_32F);
  within(area).convertTo(weights, CV_32F, 1.0 / 255.0);
  BlurWithin blur(weights);
  const cv::Mat1f fine = blur(grey, kFine), coarse = blur(grey, kCoarse);
  cv::Mat1f band, band_squared;
  cv::subtract(fine, coarse, band);
  cv::multiply(band, band, band_squared);
  cv::Mat1f energy = blur(band_squared, sigma), brightness;
  cv::add(blur(coarse, sigma), 8.0, brightness);
  cv::multiply(brightness, brightness, brightness);
  cv::Mat1f inside = out(area);
  cv::divide(energy, brightness, inside);
  return out;
}

// The image noise's share of RelativeBandEnergy: its median over the backdrop
// (`backdrop`, eroded so that no subject's edge counts), where the rig shows
// nothing but noise. 0 when too little backdrop is left.
double NoiseBandEnergy(const cv::Mat1b& grey, const cv::Mat1b& backdrop, double sigma) {
  cv::Mat1b plain;
  cv::erode(backdrop, plain, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(17, 17)));
  const cv::Mat1f energy = RelativeBandEnergy(grey, plain, sigma);
  std::vector<float> values;
  for (int y = 0; y < plain.rows; y += 4)
    for (int x = 0; x < plain.cols; x += 4)
      if (plain(y, x)) values.push_back(energy(y, x));
  if (values.size() < 100) return 0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// Fine-scale texture within the foreground (`within`): the root of
// RelativeBandEnergy. Fibres give a high value, skin little more than the
// image's noise.
cv::Mat1f TextureEnergy(const cv::Mat1b& plane, const cv::Mat1b& within, double sigma) {
  cv::Mat1f energy = RelativeBandEnergy(plane, within, sigma);
  cv::sqrt(energy, energy);
  return energy;
}

// The pixels with a channel at or above `level` (SegmentationOptions::
// clipped_level; none when it is 0), full size.
cv::Mat1b ClippedPixels(const std::vector<cv::Mat1b>& channels, int level) {
  cv::Mat1b clipped(channels[0].size(), uint8_t{0});
  if (level <= 0) return clipped;
  for (const cv::Mat1b& channel : channels) clipped |= Mask(channel >= level);
  return clipped;
}

// A clipped channel is flat where the grey image still carries the other
// channels' texture, weakly: a lock of blond hair clipped in red and green
// keeps its fibres in blue. At each pixel of `within` with a clipped channel
// (`clipped`, ClippedPixels), `energy` (TextureEnergy of the grey image)
// takes the most textured channel's (TextureEnergy of each of `channels`
// within `within`); skin clipped flat stays smooth in every channel.
void TextureWhereClipped(const std::vector<cv::Mat1b>& channels, const cv::Mat1b& within,
                         const cv::Mat1b& clipped, double sigma, cv::Mat1f& energy) {
  const cv::Mat1b any_clipped = Mask(clipped & within);
  if (cv::countNonZero(any_clipped) == 0) return;
  cv::Mat1f best(within.size(), 0.f);
  for (const cv::Mat1b& channel : channels) {
    const cv::Mat own = TextureEnergy(channel, within, sigma);
    best = cv::max(cv::Mat(best), own);
  }
  energy.forEach([&](float& e, const int* pos) {
    if (any_clipped(pos[0], pos[1])) e = best(pos[0], pos[1]);
  });
}

// A TextureEnergy value less the image noise's share (`noise_energy`,
// NoiseBandEnergy, in RelativeBandEnergy's units): what the subject's own
// texture contributes.
double TextureLessNoise(double texture, double noise_energy) {
  return std::sqrt(std::max(0.0, texture * texture - noise_energy));
}

// A pixel's features in the material model: its colour (BGR) and, when the
// model uses texture, kTextureScale log(energy + kTextureFloor). On that scale
// a doubling of the energy moves the feature by 14, about a colour channel's
// spread within one material, and the floor sits near the sensor noise's energy.
constexpr double kTextureScale = 20.0, kTextureFloor = 0.005;

// B, G, R, texture (0 without texture).
cv::Vec4d Features(const cv::Vec3b& p, float energy, bool texture) {
  const double t = texture ? kTextureScale * std::log(double(energy) + kTextureFloor) : 0.0;
  return cv::Vec4d(p[0], p[1], p[2], t);
}

// Feature rows (3 or 4 floats) of the pixels in `where`, at most `limit`, evenly spread.
cv::Mat1f FeatureSamples(const cv::Mat3b& bgr, const cv::Mat1f& energy, const cv::Mat1b& where,
                         bool texture, int limit) {
  const int count = cv::countNonZero(where);
  const int step = std::max(1, count / std::max(1, limit));
  const int dims = texture ? 4 : 3;
  cv::Mat1f samples(0, dims);
  int seen = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      if (!where(y, x) || seen++ % step != 0) continue;
      const cv::Vec4d f = Features(bgr(y, x), energy(y, x), texture);
      cv::Mat1f row(1, dims);
      for (int c = 0; c < dims; ++c) row(0, c) = static_cast<float>(f[c]);
      samples.push_back(row);
    }
  }
  return samples;
}

// The foreground's colours, and with SegmentationOptions::texture_feature
// their fine texture, as a Gaussian mixture (reconstruction/gaussian_mixture.h); each
// component is then called hair or skin by the texture of its pixels: skin is
// smooth, fibres are not. With texture in the mixture, smooth skin in shadow
// gets components of its own instead of sharing dark hair's.
class MaterialModel {
 public:
  static Result<MaterialModel> Fit(const cv::Mat3b& bgr, const cv::Mat1b& where,
                                   const cv::Mat1f& energy, double noise_energy,
                                   const SegmentationOptions& options) {
    const int components = options.colour_components;
    MaterialModel model;
    model.texture_ = options.texture_feature;
    const cv::Mat1f samples = FeatureSamples(bgr, energy, where, model.texture_, 8000);
    if (samples.rows < 20 * components)
      return FailedPrecondition("too few foreground pixels for a colour model");
    MixtureFitOptions fit;
    fit.components = components;
    fit.seed = 0x5eed5eedULL;  // so that a view segments the same on any thread, in any order
    HR_ASSIGN_OR_RETURN(const GaussianMixture mixture, FitGaussianMixture(samples, fit));
    for (const MixtureComponent& component : mixture.components) {
      Gaussian g;
      // Without texture the fourth dimension is a constant feature with the
      // same variance in every component: it adds the same constant to every term.
      cv::Matx44d cov = cv::Matx44d::eye();
      for (int r = 0; r < samples.cols; ++r) {
        g.mean[r] = component.mean[r];
        for (int c = 0; c < samples.cols; ++c) cov(r, c) = component.covariance(r, c);
      }
      // A floor of 1 on every dimension: a grey level of sensor noise on the
      // colours, a 5 % change of energy on the texture.
      cov += cv::Matx44d::eye() * 1.0;
      g.inverse = cov.inv();
      g.log_norm =
          std::log(std::max(1e-12, component.weight)) - 0.5 * std::log(cv::determinant(cov));
      model.gaussians_.push_back(g);
    }
    model.NameComponentsByTexture(bgr, where, energy, noise_energy, options.skin_texture_ratio);
    return model;
  }

  cv::Vec4d At(const cv::Mat3b& bgr, const cv::Mat1f& energy, int y, int x) const {
    return Features(bgr(y, x), energy(y, x), texture_);
  }

  // For a pixel whose colour is clipped: hair when its texture (less the
  // noise's) exceeds the threshold the components are named by, skin below;
  // 5 per factor e, clamped to +-20 as HairLogRatio.
  double HairLogRatioByTexture(float energy) const {
    const double own = TextureLessNoise(energy, noise_energy_);
    if (!(texture_threshold_ > 0)) return 0.0;
    return std::clamp(5.0 * std::log(std::max(own, 1e-9) / texture_threshold_), -20.0, 20.0);
  }

  // log p(features, hair) - log p(features, skin), clamped to +-20.
  double HairLogRatio(const cv::Vec4d& f) const {
    double hair = -1e300, skin = -1e300;
    for (const Gaussian& g : gaussians_) {
      const double t = Term(g, f);
      (g.hair ? hair : skin) = LogAdd(g.hair ? hair : skin, t);
    }
    return std::clamp(hair - skin, -20.0, 20.0);
  }

 private:
  struct Gaussian {
    cv::Vec4d mean;
    cv::Matx44d inverse;
    double log_norm = 0;
    bool hair = true;
  };

  // A component is hair when the median texture energy of the pixels it wins
  // exceeds `ratio` times the foreground's 75th percentile, which is hair's
  // whenever hair covers a quarter of the foreground (the median would be
  // skin's on a face-on view and hair's own on a back view). Where hair
  // covers less, the reference is skin's texture and textured skin may be
  // named hair. The energies are taken less the image noise's
  // (`noise_energy`, TextureLessNoise): in a grainy image noise alone would
  // make every component as textured as hair.
  void NameComponentsByTexture(const cv::Mat3b& bgr, const cv::Mat1b& where,
                               const cv::Mat1f& energy, double noise_energy, double ratio) {
    std::vector<std::vector<float>> energies(gaussians_.size());
    std::vector<float> all;
    for (int y = 0; y < bgr.rows; y += 2) {
      for (int x = 0; x < bgr.cols; x += 2) {
        if (!where(y, x)) continue;
        const auto own = static_cast<float>(TextureLessNoise(energy(y, x), noise_energy));
        energies[static_cast<size_t>(Best(At(bgr, energy, y, x)))].push_back(own);
        all.push_back(own);
      }
    }
    if (all.empty()) return;  // every component stays hair
    const double threshold = ratio * Quantile(all, 0.75);
    texture_threshold_ = threshold;
    noise_energy_ = noise_energy;
    for (size_t k = 0; k < energies.size(); ++k) {
      // A component that wins no sampled pixel is named by its mean texture
      // (with texture in the model), else it stays hair.
      const double mean_texture =
          std::max(0.0, std::exp(gaussians_[k].mean[3] / kTextureScale) - kTextureFloor);
      gaussians_[k].hair =
          energies[k].empty()
              ? !texture_ || TextureLessNoise(mean_texture, noise_energy) > threshold
              : Quantile(energies[k], 0.5) > threshold;
    }
  }
  static double Term(const Gaussian& g, const cv::Vec4d& f) {
    const cv::Vec4d d = f - g.mean;
    return g.log_norm - 0.5 * (d.t() * g.inverse * d)(0);
  }
  static double LogAdd(double a, double b) {
    if (a < b) std::swap(a, b);
    return b < -1e299 ? a : a + std::log1p(std::exp(b - a));
  }
  int Best(const cv::Vec4d& f) const {
    int best = 0;
    for (size_t k = 1; k < gaussians_.size(); ++k) {
      if (Term(gaussians_[k], f) > Term(gaussians_[static_cast<size_t>(best)], f))
        best = static_cast<int>(k);
    }
    return best;
  }
  std::vector<Gaussian> gaussians_;
  bool texture_ = true;
  double texture_threshold_ = 0, noise_energy_ = 0;
};

// A 2D Gaussian over chromaticity (r, g) = (R, G) / (R + G + B), ready to
// evaluate.
struct ChromaGaussian {
  explicit ChromaGaussian(const SkinChromaticity& model)
      : mean(model.mean),
        inverse(model.covariance.inv()),
        log_norm(-0.5 * std::log(cv::determinant(model.covariance))) {}
  cv::Vec2d mean;
  cv::Matx22d inverse;
  double log_norm = 0;  // -log det(covariance) / 2
  // Half the squared Mahalanobis distance, negated: log density up to log_norm.
  double Exponent(const cv::Vec2d& c) const {
    const cv::Vec2d d = c - mean;
    return -0.5 * (d.t() * inverse * d)(0);
  }
  double LogDensity(const cv::Vec2d& c) const { return log_norm + Exponent(c); }
};

cv::Vec2d Chromaticity(const cv::Vec3f& bgr) {
  const double sum = bgr[0] + bgr[1] + bgr[2] + 3.0;  // +1 a channel: black stays defined
  return cv::Vec2d((bgr[2] + 1.0) / sum, (bgr[1] + 1.0) / sum);
}

// No model (0 samples) for fewer than 50 samples.
SkinChromaticity FitChromaticity(const std::vector<cv::Vec2d>& samples) {
  SkinChromaticity model;
  if (samples.size() < 50) return model;
  model.samples = static_cast<int64_t>(samples.size());
  for (const cv::Vec2d& c : samples) model.mean += c;
  model.mean *= 1.0 / static_cast<double>(samples.size());
  // A floor of 0.001 in standard deviation: about a grey level on skin.
  model.covariance = cv::Matx22d::eye() * 1e-6;
  for (const cv::Vec2d& c : samples) {
    const cv::Vec2d d = c - model.mean;
    model.covariance += d * d.t() * (1.0 / static_cast<double>(samples.size()));
  }
  return model;
}

// The skin model fitted to what the mixture called skin, refitted to its core
// (within 2.5 sigma).
SkinChromaticity FitSkinCore(const std::vector<cv::Vec2d>& skin_samples) {
  const SkinChromaticity all = FitChromaticity(skin_samples);
  if (all.samples == 0) return all;
  const ChromaGaussian skin(all);
  constexpr double kCoreSigmas = 2.5;
  std::vector<cv::Vec2d> core;
  for (const cv::Vec2d& c : skin_samples)
    if (skin.Exponent(c) > -0.5 * kCoreSigmas * kCoreSigmas) core.push_back(c);
  return FitChromaticity(core);
}

// The pieces of `flips` that hold a region: an opening over 5 px, then
// connected pieces of at least `min_area` px.
cv::Mat1b CoherentPieces(const cv::Mat1b& flips, double min_area) {
  cv::Mat1b opened;
  cv::morphologyEx(flips, opened, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  cv::Mat1i labels;
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(opened, labels, stats, centroids, 8, CV_32S);
  std::vector<uint8_t> keep(static_cast<size_t>(n), 0);
  for (int k = 1; k < n; ++k)
    keep[static_cast<size_t>(k)] = stats.at<int>(k, cv::CC_STAT_AREA) >= min_area ? 255 : 0;
  cv::Mat1b out(flips.size(), uint8_t{0});
  out.forEach(
      [&](uint8_t& o, const int* pos) { o = keep[static_cast<size_t>(labels(pos[0], pos[1]))]; });
  return out;
}

struct ChromaticityStep {
  cv::Mat1b hair;
  SkinChromaticity own_skin;
  bool used_capture_skin = false;
  int64_t capture_skin_pixels = 0;  // at the working scale
};

// Skin keeps its chromaticity in shadow, where the hair's shadows give it a
// hair-like texture that the material model takes for hair. The skin's
// chromaticity is fitted on what the model calls skin (its core, within 2.5
// sigma), the hair's on what it calls hair; a hair pixel whose chromaticity
// (over a few pixels, against sensor noise) lies within `sigmas` of the skin's
// and is e^log_ratio times likelier under it than under the hair's becomes
// skin. Only the pixels of `candidates` (the foreground whose colour is not
// clipped) are fitted or turned. A view with too little skin of its own, or
// whose own does not agree with `capture_skin` (may be null), takes
// `capture_skin`, and keeps only the regions it turns to skin
// (CoherentPieces) that reach the backdrop around the subject (outside
// `foreground`) or the view's own skin, with
// options.capture_skin_touching_outline.
// Unchanged when the hair or the skin used has fewer than 50 samples.
ChromaticityStep SkinByChromaticity(const cv::Mat3b& bgr, const cv::Mat1b& candidates,
                                    const cv::Mat1b& foreground, const cv::Mat1b& hair,
                                    const SegmentationOptions& options,
                                    const SkinChromaticity* capture_skin) {
  cv::Mat3f smooth;
  bgr.convertTo(smooth, CV_32F);
  cv::GaussianBlur(smooth, smooth, cv::Size(), 1.5);
  std::vector<cv::Vec2d> skin_samples, hair_samples;
  for (int y = 0; y < bgr.rows; y += 2) {
    for (int x = 0; x < bgr.cols; x += 2) {
      if (candidates(y, x))
        (hair(y, x) ? hair_samples : skin_samples).push_back(Chromaticity(smooth(y, x)));
    }
  }
  ChromaticityStep step;
  step.hair = hair;
  step.own_skin = FitSkinCore(skin_samples);
  const SkinChromaticity hair_fit = FitChromaticity(hair_samples);
  step.used_capture_skin = capture_skin != nullptr && capture_skin->samples > 0 &&
                           (step.own_skin.samples < options.skin_chromaticity_min_view_samples ||
                            !SkinModelAgrees(step.own_skin, *capture_skin));
  const SkinChromaticity& skin_fit = step.used_capture_skin ? *capture_skin : step.own_skin;
  if (hair_fit.samples == 0 || skin_fit.samples == 0) return step;
  const ChromaGaussian skin(skin_fit), hair_model(hair_fit);
  const double sigmas = options.skin_chromaticity_sigmas;
  cv::Mat1b flips(hair.size(), uint8_t{0});
  flips.forEach([&](uint8_t& f, const int* pos) {
    if (!hair(pos[0], pos[1]) || !candidates(pos[0], pos[1])) return;
    const cv::Vec2d c = Chromaticity(smooth(pos[0], pos[1]));
    if (skin.Exponent(c) > -0.5 * sigmas * sigmas &&
        skin.LogDensity(c) - hair_model.LogDensity(c) > options.skin_chromaticity_log_ratio)
      f = 255;
  });
  if (step.used_capture_skin) {
    const double scale = options.work_scale;
    flips = CoherentPieces(flips, options.capture_skin_min_area_px * scale * scale);
    if (options.capture_skin_touching_outline)
      flips = PiecesTouching(flips, Mask(OuterBackdrop(foreground) | (candidates & ~hair)), 3);
    step.capture_skin_pixels = cv::countNonZero(flips);
  }
  step.hair = Mask(hair & ~flips);
  return step;
}

// The distance (grey levels) from colour `p` to the nearest non-negative mix
// a c + b backdrop with a + b <= 1: `c` blended with the backdrop over a
// pixel, in shade or not.
double DistanceToBlend(const cv::Vec3d& p, const cv::Vec3d& c, const cv::Vec3d& backdrop) {
  const auto residual = [&](double a, double b) { return cv::norm(p - a * c - b * backdrop); };
  const auto unit = [](double t) { return std::clamp(t, 0.0, 1.0); };
  // The least-squares mix, then the three edges of the allowed triangle.
  const double cc = c.dot(c), bb = backdrop.dot(backdrop), cb = c.dot(backdrop);
  const double pc = p.dot(c), pb = p.dot(backdrop), det = cc * bb - cb * cb;
  double best = std::numeric_limits<double>::infinity();
  if (det > 1e-9) {
    const double a = (pc * bb - pb * cb) / det, b = (pb * cc - pc * cb) / det;
    if (a >= 0 && b >= 0 && a + b <= 1) best = residual(a, b);
  }
  if (cc > 0) best = std::min(best, residual(unit(pc / cc), 0));
  if (bb > 0) best = std::min(best, residual(0, unit(pb / bb)));
  const cv::Vec3d d = c - backdrop;
  const double dd = d.dot(d);
  const double t = dd > 0 ? unit((p - backdrop).dot(d) / dd) : 0;
  return std::min(best, residual(t, 1 - t));
}

// The colour of the pixels in `where` around each pixel (a Gaussian of
// `sigma` px over them only) and their weight there (0 where none is near).
struct LocalColour {
  cv::Mat3f colour;
  cv::Mat1f weight;
};

LocalColour LocalColourOf(const cv::Mat3f& bgr, const cv::Mat1b& where, double sigma) {
  LocalColour out;
  cv::Mat1f w;
  where.convertTo(w, CV_32F, 1.0 / 255.0);
  std::vector<cv::Mat1f> channels;
  cv::split(bgr, channels);
  BlurWithin blur(w);
  for (cv::Mat1f& channel : channels) channel = blur(channel, sigma);
  cv::merge(channels, out.colour);
  out.weight = blur.Weight(sigma);
  return out;
}

// The hair pixels (working scale) that SegmentationOptions::outline_blend_sigmas
// calls blends of skin with the backdrop along the foreground's outline.
cv::Mat1b OutlineBlendsOfSkin(const cv::Mat3b& bgr, const cv::Mat1b& candidates,
                              const cv::Mat1b& hair, const BackdropModel& backdrop, double sigmas) {
  constexpr double kLocalSigmaPx = 3, kMinWeight = 0.05;
  const cv::Mat ellipse5 = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5));
  cv::Mat1b near_backdrop, hair_core;
  cv::dilate(Mask(candidates == 0), near_backdrop, ellipse5);
  cv::erode(hair, hair_core, ellipse5);
  cv::Mat3f colours;
  bgr.convertTo(colours, CV_32F);
  const LocalColour skin = LocalColourOf(colours, Mask(candidates & ~hair), kLocalSigmaPx);
  const LocalColour hair_beside = LocalColourOf(colours, hair_core, kLocalSigmaPx);
  const double tolerance = sigmas * std::max(backdrop.sigma, 2.0);
  cv::Mat1b blends(hair.size(), uint8_t{0});
  blends.forEach([&](uint8_t& out, const int* pos) {
    const int y = pos[0], x = pos[1];
    if (!hair(y, x) || !near_backdrop(y, x) || skin.weight(y, x) < kMinWeight) return;
    const cv::Vec3d p(bgr(y, x)[0], bgr(y, x)[1], bgr(y, x)[2]);
    const double to_skin = DistanceToBlend(p, cv::Vec3d(skin.colour(y, x)), backdrop.mean);
    if (to_skin > tolerance) return;
    if (hair_beside.weight(y, x) >= kMinWeight &&
        DistanceToBlend(p, cv::Vec3d(hair_beside.colour(y, x)), backdrop.mean) <= to_skin)
      return;
    out = 255;
  });
  return blends;
}

// The foreground's pixels whose colour is clipped at the working scale: those
// over which any full-size pixel of `full_clipped` (ClippedPixels) lies, in
// patches (an opening over 3 px: a highlight clips over a patch, grain on a
// bright surface clips single pixels). `candidates`: the foreground at the
// working scale. None when fewer than a quarter of the candidates are left
// unclipped (too few to model the materials on).
cv::Mat1b ClippedCandidates(const cv::Mat1b& full_clipped, const cv::Mat1b& candidates) {
  cv::Mat1b patches;
  cv::morphologyEx(full_clipped, patches, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  cv::Mat1b small;  // non-zero where any full-size pixel under the small one clips
  cv::resize(patches, small, candidates.size(), 0, 0, cv::INTER_AREA);
  const cv::Mat1b clipped = Mask(candidates & (small > 0));
  const int clipped_count = cv::countNonZero(clipped);
  const int all = cv::countNonZero(candidates);
  return 4 * (all - clipped_count) < all ? cv::Mat1b(candidates.size(), uint8_t{0}) : clipped;
}

// Hair against skin on the foreground (non-zero in `candidates`): the
// material model's likelihood ratio, smoothed over a few pixels. The model is
// fitted on the pixels not `clipped`; a clipped pixel's colour says nothing of
// its material, and it is hair or skin by its texture alone
// (MaterialModel::HairLogRatioByTexture). Returns a mask of hair, same size
// as `bgr`.
Result<cv::Mat1b> HairBySkinContrast(const cv::Mat3b& bgr, const cv::Mat1b& candidates,
                                     const cv::Mat1b& clipped, const cv::Mat1f& energy,
                                     double noise_energy, const SegmentationOptions& options) {
  HR_ASSIGN_OR_RETURN(
      const MaterialModel model,
      MaterialModel::Fit(bgr, Mask(candidates & ~clipped), energy, noise_energy, options));
  cv::Mat1f ratio(bgr.size(), 0.f);
  ratio.forEach([&](float& r, const int* pos) {
    if (!candidates(pos[0], pos[1])) return;
    r = static_cast<float>(clipped(pos[0], pos[1])
                               ? model.HairLogRatioByTexture(energy(pos[0], pos[1]))
                               : model.HairLogRatio(model.At(bgr, energy, pos[0], pos[1])));
  });
  cv::GaussianBlur(ratio, ratio, cv::Size(), options.texture_sigma_px * options.work_scale);
  return Mask(candidates & (ratio > 0));
}

cv::Mat3b AsBgr(const cv::Mat& image) {
  if (image.channels() == 3) return image;
  cv::Mat3b bgr;
  cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

// Hair-like pixels in pieces smaller than `share` of the largest piece: specks
// and thin lines apart from the hair, not the subject.
cv::Mat1b StrayComponents(const cv::Mat1b& hair, double share) {
  cv::Mat1i labels;
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(hair, labels, stats, centroids, 8, CV_32S);
  int largest = 0;
  for (int k = 1; k < n; ++k) largest = std::max(largest, stats.at<int>(k, cv::CC_STAT_AREA));
  std::vector<uint8_t> is_stray(static_cast<size_t>(n), 0);
  for (int k = 1; k < n; ++k)
    is_stray[static_cast<size_t>(k)] = stats.at<int>(k, cv::CC_STAT_AREA) < share * largest;
  cv::Mat1b stray(hair.size(), uint8_t{0});
  for (int y = 0; y < hair.rows; ++y)
    for (int x = 0; x < hair.cols; ++x)
      stray(y, x) = is_stray[static_cast<size_t>(labels(y, x))] ? 255 : 0;
  return stray;
}

}  // namespace

Status SegmentationOptions::Check() const {
  if (border_px < 2) return InvalidArgument("segmentation border_px must be at least 2");
  if (!(backdrop_distance > 0))
    return InvalidArgument("segmentation backdrop_distance must be positive");
  if (!(texture_sigma_px > 0))
    return InvalidArgument("segmentation texture_sigma_px must be positive");
  if (!(skin_texture_ratio > 0 && skin_texture_ratio < 1)) {
    return InvalidArgument("segmentation skin_texture_ratio must be in (0, 1)");
  }
  if (!(skin_chromaticity_sigmas >= 0))
    return InvalidArgument("segmentation skin_chromaticity_sigmas must be non-negative (0: off)");
  if (!(skin_chromaticity_log_ratio >= 0))
    return InvalidArgument("segmentation skin_chromaticity_log_ratio must be non-negative");
  if (skin_chromaticity_min_view_samples < 50)
    return InvalidArgument("segmentation skin_chromaticity_min_view_samples must be at least 50");
  if (!(capture_skin_min_area_px >= 0))
    return InvalidArgument("segmentation capture_skin_min_area_px must be non-negative");
  if (colour_components < 1 || colour_components > 8) {
    return InvalidArgument("segmentation colour_components must be in 1..8");
  }
  if (!(min_hair_component_share >= 0 && min_hair_component_share < 1))
    return InvalidArgument("segmentation min_hair_component_share must be in [0, 1)");
  if (!(outline_blend_sigmas >= 0))
    return InvalidArgument("segmentation outline_blend_sigmas must be non-negative (0: off)");
  if (clipped_level < 0 || clipped_level > 255)
    return InvalidArgument("segmentation clipped_level must be a grey level in 0..255 (0: off)");
  if (!(work_scale > 0.1 && work_scale <= 1))
    return InvalidArgument("segmentation work_scale must be in (0.1, 1]");
  return Status::Ok();
}

SkinChromaticity PoolSkinChromaticity(const std::vector<SkinChromaticity>& views) {
  SkinChromaticity pooled;
  for (const SkinChromaticity& v : views) {
    pooled.samples += v.samples;
    pooled.mean += v.mean * static_cast<double>(v.samples);
  }
  if (pooled.samples == 0) return pooled;
  const double total = static_cast<double>(pooled.samples);
  pooled.mean *= 1.0 / total;
  pooled.covariance = cv::Matx22d::zeros();
  for (const SkinChromaticity& v : views) {
    const cv::Vec2d d = v.mean - pooled.mean;
    pooled.covariance += (v.covariance + d * d.t()) * (static_cast<double>(v.samples) / total);
  }
  return pooled;
}

namespace {

// The value below and above which half the weight lies (pairs of value and
// weight; not empty).
double WeightedMedian(std::vector<std::pair<double, double>> values) {
  std::sort(values.begin(), values.end());
  double total = 0;
  for (const auto& [value, weight] : values) total += weight;
  double below = 0;
  for (const auto& [value, weight] : values) {
    below += weight;
    if (below >= 0.5 * total) return value;
  }
  return values.back().first;
}

double LargerDeviation(const SkinChromaticity& model) {
  return std::sqrt(std::max(model.covariance(0, 0), model.covariance(1, 1)));
}

}  // namespace

bool SkinModelAgrees(const SkinChromaticity& own, const SkinChromaticity& reference) {
  if (own.samples == 0 || reference.samples == 0) return false;
  constexpr double kMinTolerance = 0.01, kSigmas = 3;
  const double tolerance = std::max(kMinTolerance, kSigmas * LargerDeviation(reference));
  return cv::norm(own.mean - reference.mean) <= tolerance;
}

SkinChromaticity CaptureSkinChromaticity(const std::vector<SkinChromaticity>& views) {
  std::vector<std::pair<double, double>> r, g, deviation;
  for (const SkinChromaticity& v : views) {
    if (v.samples == 0) continue;
    const double weight = static_cast<double>(v.samples);
    r.emplace_back(v.mean[0], weight);
    g.emplace_back(v.mean[1], weight);
    deviation.emplace_back(LargerDeviation(v), weight);
  }
  if (r.empty()) return SkinChromaticity{};
  SkinChromaticity consensus;
  consensus.samples = 1;
  consensus.mean = cv::Vec2d(WeightedMedian(r), WeightedMedian(g));
  const double sd = WeightedMedian(deviation);
  consensus.covariance = cv::Matx22d::eye() * (sd * sd);
  std::vector<SkinChromaticity> agreeing;
  for (const SkinChromaticity& v : views)
    if (SkinModelAgrees(v, consensus)) agreeing.push_back(v);
  return PoolSkinChromaticity(agreeing);
}

std::vector<Result<HairSegmentation>> SegmentCaptureViews(
    size_t views, const SegmentationOptions& options, int threads,
    const std::function<Result<HairSegmentation>(size_t, const SkinChromaticity*)>& segment) {
  std::vector<Result<HairSegmentation>> out(
      views, Result<HairSegmentation>(FailedPrecondition("not segmented")));
  ParallelFor(views, threads, [&] { return [&](size_t v) { out[v] = segment(v, nullptr); }; });
  const auto has_own = [&](size_t v) {
    return out[v]->skin_chromaticity.samples >= options.skin_chromaticity_min_view_samples;
  };
  std::vector<SkinChromaticity> own;
  for (size_t v = 0; v < views; ++v)
    if (out[v].ok() && has_own(v)) own.push_back(out[v]->skin_chromaticity);
  const SkinChromaticity capture_skin = CaptureSkinChromaticity(own);
  if (capture_skin.samples == 0 || options.skin_chromaticity_sigmas <= 0 || !options.capture_skin)
    return out;
  std::vector<size_t> again;
  for (size_t v = 0; v < views; ++v) {
    if (out[v].ok() && (!has_own(v) || !SkinModelAgrees(out[v]->skin_chromaticity, capture_skin)))
      again.push_back(v);
  }
  ParallelFor(again.size(), threads, [&] {
    return [&](size_t k) {
      Result<HairSegmentation> second = segment(again[k], &capture_skin);
      if (second.ok()) out[again[k]] = std::move(second);
    };
  });
  return out;
}

std::vector<cv::Point2f> ProjectedOutline(const CameraIntrinsics& camera,
                                          const Rigid3d& cam_from_points,
                                          const std::vector<Eigen::Vector3d>& points) {
  std::vector<cv::Point2f> projected, hull;
  for (const Eigen::Vector3d& p : points) {
    Eigen::Vector2d uv;
    if (ProjectChecked(camera, cam_from_points * p, &uv))
      projected.emplace_back(float(uv.x()), float(uv.y()));
  }
  if (projected.size() < 3) return {};
  cv::convexHull(projected, hull);
  return hull;
}

Result<HairSegmentation> SegmentHair(const cv::Mat& image,
                                     const std::vector<std::vector<cv::Point2f>>& not_hair_px,
                                     const SegmentationOptions& options,
                                     const SkinChromaticity* capture_skin) {
  HR_RETURN_IF_ERROR(options.Check());
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    return InvalidArgument("segmentation needs an 8-bit grey or BGR image");
  }
  if (image.cols <= 4 * options.border_px || image.rows <= 4 * options.border_px) {
    return InvalidArgument("segmentation: the image is too small for a border of " +
                           std::to_string(options.border_px) + " px");
  }
  const cv::Mat3b bgr = AsBgr(image);
  HR_ASSIGN_OR_RETURN(const BackdropModel backdrop, FitBackdrop(bgr, options.border_px));
  const cv::Mat1f distance = BackdropDistance(bgr, backdrop);
  const cv::Mat1b foreground = Mask(distance >= options.backdrop_distance);

  cv::Mat1b box_region(bgr.size(), uint8_t{0});
  for (const auto& polygon : not_hair_px) {
    std::vector<cv::Point> points;
    for (const cv::Point2f& p : polygon) points.emplace_back(cvRound(p.x), cvRound(p.y));
    if (points.size() >= 3)
      cv::fillPoly(box_region, std::vector<std::vector<cv::Point>>{points}, cv::Scalar(255));
  }
  const cv::Mat1b candidates = Mask(foreground & ~box_region);
  if (cv::countNonZero(candidates) < 100) {
    return FailedPrecondition(
        "nothing but backdrop and box in the image (no subject in view, or a black frame)");
  }

  // The colour model and graph cut at the working scale.
  const double s = options.work_scale;
  cv::Mat3b small_bgr;
  cv::Mat1b small_candidates;
  cv::Mat1f small_energy;
  cv::resize(bgr, small_bgr, cv::Size(), s, s, cv::INTER_AREA);
  cv::resize(candidates, small_candidates, small_bgr.size(), 0, 0, cv::INTER_AREA);
  small_candidates = Mask(small_candidates >= 128);
  cv::Mat1b grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  const double noise_energy =
      options.texture_less_noise ? NoiseBandEnergy(grey, Mask(distance < options.backdrop_distance),
                                                   options.texture_sigma_px)
                                 : 0.0;
  std::vector<cv::Mat1b> channels;
  cv::split(bgr, channels);
  const cv::Mat1b full_clipped = ClippedPixels(channels, options.clipped_level);
  cv::Mat1f energy = TextureEnergy(grey, candidates, options.texture_sigma_px);
  TextureWhereClipped(channels, candidates, full_clipped, options.texture_sigma_px, energy);
  cv::resize(energy, small_energy, small_bgr.size(), 0, 0, cv::INTER_AREA);
  const cv::Mat1b clipped = ClippedCandidates(full_clipped, small_candidates);
  HR_ASSIGN_OR_RETURN(const cv::Mat1b contrast_hair,
                      HairBySkinContrast(small_bgr, small_candidates, clipped, small_energy,
                                         noise_energy, options));
  ChromaticityStep chromaticity;
  chromaticity.hair = contrast_hair;
  if (options.skin_chromaticity_sigmas > 0)
    chromaticity = SkinByChromaticity(small_bgr, Mask(small_candidates & ~clipped),
                                      small_candidates, contrast_hair, options, capture_skin);
  cv::Mat1b small_hair = chromaticity.hair;
  if (options.outline_blend_sigmas > 0)
    small_hair = Mask(small_hair & ~OutlineBlendsOfSkin(small_bgr, small_candidates, small_hair,
                                                        backdrop, options.outline_blend_sigmas));
  cv::Mat1b hair_side;
  cv::resize(small_hair, hair_side, bgr.size(), 0, 0, cv::INTER_LINEAR);
  hair_side = Mask(hair_side >= 128);
  // Foreground pixels the small scale lost (thin strands at the silhouette)
  // take the side of the hair within a few pixels.
  cv::Mat1b skin_side;
  cv::resize(Mask(small_candidates & ~small_hair), skin_side, bgr.size(), 0, 0, cv::INTER_LINEAR);
  skin_side = Mask(skin_side >= 128);
  cv::Mat1b near_hair;
  cv::dilate(hair_side, near_hair, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7)));
  const cv::Mat1b hair_region = Mask(candidates & (hair_side | (near_hair & ~skin_side)));
  if (cv::countNonZero(hair_region) < 50)
    return FailedPrecondition("no pixel looks like hair in the image");

  // Coverage against the backdrop: the distance relative to the hair's own.
  std::vector<float> hair_distances;
  for (int y = 0; y < bgr.rows; y += 2) {
    for (int x = 0; x < bgr.cols; x += 2) {
      if (hair_region(y, x)) hair_distances.push_back(distance(y, x));
    }
  }
  const float full_coverage = std::max(static_cast<float>(2 * options.backdrop_distance),
                                       static_cast<float>(Quantile(hair_distances, 0.5)));

  const cv::Mat1b stray = StrayComponents(hair_region, options.min_hair_component_share);
  const cv::Mat1b shadowed_skin =
      options.opaque_shadow_as_skin ? OpaqueShadowOnSkin(bgr, hair_region, distance, full_coverage,
                                                         backdrop, Mask(candidates & ~hair_region),
                                                         options.opaque_shadow_touching_skin_only)
                                    : cv::Mat1b(bgr.size(), uint8_t{0});
  HairSegmentation out;
  out.backdrop_sigma = backdrop.sigma;
  out.skin_chromaticity = chromaticity.own_skin;
  out.used_capture_skin = chromaticity.used_capture_skin;
  out.capture_skin_pixels = static_cast<int64_t>(
      std::lround(static_cast<double>(chromaticity.capture_skin_pixels) / (s * s)));
  out.label = cv::Mat1b(bgr.size(), uint8_t{kSegBackdrop});
  out.hair_alpha = cv::Mat1f(bgr.size(), 0.f);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      if (!foreground(y, x) || stray(y, x)) continue;
      if (box_region(y, x)) {
        out.label(y, x) = kSegBox;
        continue;
      }
      if (!hair_region(y, x)) {
        out.label(y, x) = kSegHead;
        continue;
      }
      const float alpha = std::min(1.f, distance(y, x) / full_coverage);
      if (shadowed_skin(y, x)) {
        out.label(y, x) = kSegHead;
        continue;
      }
      out.hair_alpha(y, x) = alpha;
      out.label(y, x) = alpha >= 0.5f ? kSegHair : kSegBackdrop;
    }
  }
  return out;
}

}  // namespace hairrig
