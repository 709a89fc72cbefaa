// Per-view segmentation of a hair capture into backdrop, calibration box,
// head (skin) and hair, with a soft hair coverage (alpha).
//
// Keying as Bao & Qi 2017 Sec. III (a colour classifier seeded by what the rig
// knows), in three steps:
//  1. backdrop: the colour of the image's border band (the rig's backdrop
//     fills it) as a Gaussian in BGR; a pixel's Mahalanobis distance to it
//     gives the backdrop, and the hair's coverage where hair is seen against it
//     (alpha = distance / the distance of the hair's own colour); a pixel of
//     the hair's region too dark to be a blend of hair over the backdrop
//     (SegmentationOptions::opaque_shadow_as_skin) is skin in the hair's
//     shadow, not backdrop;
//  2. box: the polygons the caller knows hold no hair (the calibration box's
//     projected outline) are box wherever they are not backdrop;
//  3. hair against skin: the foreground's colours and fine texture (a
//     band-pass energy) as a Gaussian mixture (EM); fibres make a fine
//     texture that skin lacks, so each component is hair or skin by the
//     texture of the pixels it explains; the likelihood ratio of the two,
//     smoothed over a few pixels, labels every pixel. Texture in the mixture
//     keeps smooth skin in shadow out of dark hair's components; without it
//     (`texture_feature` false) the mixture is over colour alone, as Bao &
//     Qi's. A pixel with a clipped channel is named by its texture alone
//     (SegmentationOptions::clipped_level). Skin in shadow keeps its
//     chromaticity: hair pixels whose chromaticity the skin's explains far
//     better become skin. A view that
//     shows too little lit skin to model it (the back of the head, where the
//     neck lies in the hair's shadow) borrows the capture's: the models of
//     the views that have one and agree, pooled (SegmentCaptureViews runs the
//     two passes), and turns only regions that reach the subject's outline.
// Labels use the simulated ground truth's numbering (core/truth_maps.h) so that
// they compare directly.
#pragma once

#include <cstdint>
#include <functional>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "core/camera_model.h"
#include "core/status.h"
#include "core/transform.h"

namespace hairrig {

enum SegmentLabel : uint8_t { kSegBackdrop = 0, kSegBox = 1, kSegHead = 2, kSegHair = 3 };

struct SegmentationOptions {
  int border_px = 16;  // the band along the image's edges that shows the backdrop
  double backdrop_distance =
      6.0;  // Mahalanobis distance to the backdrop colour under which a pixel is backdrop
  double texture_sigma_px = 4.0;  // window over which the fine-scale energy is averaged
  int colour_components = 6;      // Gaussians in the foreground's colour (and texture) model
  bool texture_feature = true;    // the mixture models texture beside colour
  // Components are named hair or skin by their texture less the image
  // noise's, measured over the backdrop: in a grainy image (high ISO, a path
  // tracer's few samples) noise alone makes smooth skin as textured as hair.
  // false keeps the noise in.
  bool texture_less_noise = true;
  // A component is skin when its pixels' median texture is below this share
  // of the foreground's 75th percentile (hair's texture when hair covers at
  // least a quarter of the foreground; on a view with less hair than that,
  // textured skin may be taken for hair).
  double skin_texture_ratio = 0.35;
  // Skin in shadow under hair carries the hair's shadows, a fine texture
  // that the mixture takes for hair, but it keeps the skin's chromaticity:
  // a pixel named hair whose chromaticity lies within skin_chromaticity_sigmas
  // of the skin's, and is e^skin_chromaticity_log_ratio times likelier under
  // the skin's than under the hair's, is skin (2D Gaussians fitted per view
  // to what the mixture named each). 0 sigmas turns it off. The hair's
  // Gaussian takes in the shadowed skin the mixture named hair, which pulls
  // it towards the skin's; hence a low ratio: under a camera's tone curve,
  // where blond hair and pale skin lie close, e^5 leaves most of that skin
  // hair (docs/accuracy.md, "Strands in front of skin").
  double skin_chromaticity_sigmas = 3.0;
  double skin_chromaticity_log_ratio = 2.0;
  // A view whose own skin model rests on fewer pixels than this (at
  // work_scale, every 2nd row and column), or does not agree with the
  // capture's (SkinModelAgrees), uses the capture's model when one is given. capture_skin false:
  // SegmentCaptureViews segments each view alone.
  int skin_chromaticity_min_view_samples = 500;
  bool capture_skin = true;
  // Pixels turned to skin by the capture's model count only in pieces of at
  // least this area (px at full size, after an opening over 5 px at
  // work_scale): the skin under the hair's shadow is a region, where hair
  // whose glints happen to match the skin's chromaticity is scattered.
  double capture_skin_min_area_px = 600;
  // ... and only in pieces that reach (within 3 px at work_scale) the
  // backdrop around the subject (connected to the image's border) or the
  // skin the view's own material model found: the neck in the hair's shadow
  // runs on to the silhouette's edge, while hair in shadow whose
  // chromaticity the capture's model explains lies within the hair (the
  // back views of a dimly lit head; docs/accuracy.md, "Hair segmentation").
  // false: every piece large enough.
  bool capture_skin_touching_outline = true;
  // A pixel of the hair's region whose colour lies nearer the backdrop than
  // half the hair's (coverage under 0.5, a blend) yet is too dark to be a
  // blend (it hides at least half of the backdrop's light in some channel):
  // opaque and darker than the hair, skin in shadow under the hair (the
  // neck beneath the jaw) or a shadowed gap between locks. true: labelled
  // skin, so that the strands' skin tests see the shadowed neck; false:
  // backdrop, as a blend's.
  bool opaque_shadow_as_skin = true;
  // With opaque_shadow_as_skin, only the pieces of such pixels that touch
  // the skin the material model found (within 3 px) are skin: skin in
  // shadow continues lit skin, while the gaps between locks, as opaque and
  // as dark, lie within the hair and stay backdrop. A gap taken for skin
  // ends the strands that cross it (most of all against a dark blue
  // backdrop, which every shadowed blond pixel hides); skin seen through a
  // gap, left backdrop, no longer ends them.
  bool opaque_shadow_touching_skin_only = false;
  // Along the foreground's outline a pixel blends the subject with the
  // backdrop (the lens, the sensor's pixel, defocus), and a blend of skin in
  // shade with the backdrop can look like hair to the material model: a rim
  // of "hair" along the neck's or the face's outline, which several views
  // agree on where the outline is a sharp edge (a mannequin's neck cut). A
  // hair pixel at the working scale within 2 px of the backdrop, with skin
  // beside it, whose colour is a non-negative mix of the skin's beside it
  // and the backdrop's (total weight at most 1, shade allowed) to within
  // outline_blend_sigmas of the backdrop's noise, and nearer such a mix than
  // a mix of the hair's beside it (where there is hair), is skin. 0 turns
  // it off.
  double outline_blend_sigmas = 3.0;
  // A pixel with a channel at or above this grey level is clipped: an
  // over-exposed highlight, whose colour says nothing of its material (blond
  // hair's locks and pale skin both clip to near white). Clipped pixels, in
  // patches of 3 px or more, are left out of the material model and of the
  // chromaticity fits, and are hair or skin by their texture alone: the most
  // textured channel's (a lock clipped in red and green keeps its fibres in
  // blue; clipped skin is flat in every channel) against the threshold the
  // model's components are named by. When fewer than a quarter of the
  // foreground's pixels are unclipped, every pixel is modelled by its colour.
  // 0 turns it off (docs/accuracy.md, "Hair segmentation").
  int clipped_level = 250;
  double work_scale = 0.5;  // the colour model and graph cut run at this scale (1 = full size)
  // Hair pieces smaller than this share of the largest are not hair (specks,
  // thin lines of the rig apart from the subject): labelled backdrop.
  double min_hair_component_share = 0.01;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

// Skin as a 2D Gaussian over chromaticity (r, g) = (R, G) / (R + G + B).
struct SkinChromaticity {
  cv::Vec2d mean{0, 0};
  cv::Matx22d covariance = cv::Matx22d::eye();
  int64_t samples = 0;  // pixels it was fitted to; 0: no model
};

// The models of several views as one: the Gaussian of their samples taken
// together (means and covariances combined by sample count). No model (0
// samples) when none of them has one.
SkinChromaticity PoolSkinChromaticity(const std::vector<SkinChromaticity>& views);

// Whether a view's own skin model agrees with `reference`: their means lie
// within max(0.01, 3 x the reference's larger standard deviation) in
// chromaticity (the view's own spread does not count). A view whose mixture named the backdrop or
// hair its skin (an under-exposed back view, with no lit skin in sight) lies
// far off. False when either has no model.
bool SkinModelAgrees(const SkinChromaticity& own, const SkinChromaticity& reference);

// The capture's skin from the views' own models: those that agree
// (SkinModelAgrees) with the models' consensus (the sample-weighted median of
// their means and of their standard deviations, each coordinate on its
// own), pooled (PoolSkinChromaticity). No model when none of them has one or
// none agrees (the median of r and g apart can lie away from every view).
SkinChromaticity CaptureSkinChromaticity(const std::vector<SkinChromaticity>& views);

struct HairSegmentation {
  cv::Mat1b label;       // SegmentLabel per pixel, full size
  cv::Mat1f hair_alpha;  // hair coverage 0..1 (0 off the hair); label is hair where alpha >= 0.5
  double backdrop_sigma = 0;  // the backdrop's colour spread (grey levels, mean of the channels)
  // The view's own skin model (its core), 0 samples when the view shows too
  // little skin; whether the capture's pooled model was used instead.
  SkinChromaticity skin_chromaticity;
  bool used_capture_skin = false;
  int64_t capture_skin_pixels = 0;  // pixels (full size) the capture's model turned to skin
};

// The outline (convex hull, px) of 3D points seen by a camera: how the rig
// turns the calibration box's corners into a not-hair polygon. Points behind
// the camera are skipped; fewer than three in front give an empty outline.
std::vector<cv::Point2f> ProjectedOutline(const CameraIntrinsics& camera,
                                          const Rigid3d& cam_from_points,
                                          const std::vector<Eigen::Vector3d>& points);

// `image`: 8-bit BGR or grey. `not_hair_px`: polygons in pixels (may be
// empty). InvalidArgument for an empty image or bad options; FailedPrecondition
// when the border is not a backdrop (too varied: the subject or box touches
// the edge, or the frame is black) or no pixel looks like hair.
// `capture_skin` (may be null) stands in for the view's own skin model when
// that rests on fewer than options.skin_chromaticity_min_view_samples or does
// not agree with it (SkinModelAgrees).
Result<HairSegmentation> SegmentHair(const cv::Mat& image,
                                     const std::vector<std::vector<cv::Point2f>>& not_hair_px,
                                     const SegmentationOptions& options,
                                     const SkinChromaticity* capture_skin = nullptr);

// Segments the views of one capture in two passes: every view with its own
// skin model, then the views whose own model rests on fewer than
// options.skin_chromaticity_min_view_samples, or does not agree with the
// capture's, again with the capture's (CaptureSkinChromaticity). `segment(v, capture_skin)`
// segments view v (capture_skin null in the first pass) with `options`, may be called from
// `threads` threads at once and must not throw. Returns each view's result;
// a view that fails in the first pass is not tried again, one that fails in
// the second keeps its first.
std::vector<Result<HairSegmentation>> SegmentCaptureViews(
    size_t views, const SegmentationOptions& options, int threads,
    const std::function<Result<HairSegmentation>(size_t view,
                                                 const SkinChromaticity* capture_skin)>& segment);

}  // namespace hairrig
