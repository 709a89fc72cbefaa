// Renders what a simulated camera sees: backdrop, head (an ellipsoid or a
// mesh, skin-shaded), calibration box with its AprilTags, and the hair,
// through the camera's lens distortion, depth of field, exposure, sensor noise
// and processing (sim_hw/camera_pipeline.h: all but distortion, exposure and
// noise are off unless the scene's camera_pipeline turns them on).
//
// Geometry is exact where calibration depends on it: the box and the head are
// ray-cast per pixel through the inverse of the lens model (no image warping),
// and box pixels on an edge are integrated with 8 x 8 stratified samples, so
// tag corners land where the camera model projects them.
//
// Hair: every fibre segment is drawn with its true coverage: a fibre of
// diameter w at depth z covers w f / z pixels across (about 0.12 px for 70 um
// at 1 m), spread over the pixels within one pixel of its centre line by a
// tent filter, composited back to front. Fibres are shaded with R, TT and TRT
// lobes (sim_hw/hair_shading.h), each fibre optionally with its own shade and
// a grain of glints along it (HairShading), and shadowed by a deep opacity map per LED
// panel (sim_hw/deep_opacity.h), which also darkens the head under the hair.
// All panels off gives a dark frame (noise only).
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "core/truth_maps.h"
#include "sim_hw/scene.h"

namespace hairrig {

struct RenderOptions {
  std::vector<double> light_levels;  // one per scene light, 0..1; empty = all on
  double exposure_s = 0;             // 0 = the camera's nominal exposure
  double gain_db = 0;
  bool noise = true;
  uint64_t noise_seed = 0;  // same seed, same noise
  bool draw_hair = true;
  int threads = 2;            // for the hair and the head (a view is split in bands)
  bool ground_truth = false;  // fill RenderedView::truth
  bool shade_hair = true;     // false: fibres drawn unlit and no shadow maps built (for
                           // ground-truth maps alone: the geometry is the same, the image is not)
  bool keep_radiance = false;  // fill RenderedView::radiance

  // InvalidArgument naming the field: a light level outside 0..1, a negative
  // or non-finite exposure, a non-finite gain, threads below 1.
  Status Check() const;
};

// Ground truth of one tag in one rendered view.
struct TagTruth {
  int id = -1;
  std::array<Eigen::Vector2d, 4> corners_px;  // projections, libapriltag corner order
  double facing_deg = 0;    // elevation of the viewing ray above the face plane; <= 0: back-facing
  bool in_image = false;    // all corners at least 4 px inside the image
  bool unoccluded = false;  // no head or hair over any part of the printed tag
};

struct RenderedView {
  cv::Mat image;  // CV_8UC3, BGR
  std::vector<TagTruth> tags;
  ViewTruthMaps truth;  // with RenderOptions::ground_truth only
  cv::Mat3f
      radiance;  // linear scene radiance before exposure; with RenderOptions::keep_radiance only
};

class HeadModel;

class Renderer {
 public:
  // Builds the head, generates the wig and precomputes per-camera ray tables.
  // Keeps a copy of `scene`. Errors name the scene's field (head.mesh, wig.file).
  static Result<std::unique_ptr<Renderer>> Create(const Scene& scene);
  ~Renderer();

  const Scene& scene() const;
  const StrandSet& strands_turntable_mm() const;  // the wig, turntable frame
  const HeadModel& head() const;
  // Replaces the wig (turntable frame, mm), e.g. with a simulated frame of it.
  // Not safe while another thread renders.
  void SetStrands(StrandSet strands_turntable_mm);

  // OutOfRange for a camera index outside the scene; InvalidArgument for bad
  // options (RenderOptions::Check) or light levels of the wrong count. Thread-safe (const). The
  // hair's buffers of up to two finished renders are kept for the next ones (a few hundred MB for a
  // 50,000-strand wig), for as long as the renderer lives.
  Result<RenderedView> Render(int camera_index, double turntable_deg,
                              const RenderOptions& options) const;
  // The 8-bit BGR image camera `camera_index` records of `radiance` (a
  // RenderedView::radiance of that camera) with `options`' exposure, gain and
  // noise: the same image Render gives for those options. OutOfRange for a
  // camera outside the scene, InvalidArgument for bad options or a radiance
  // of another size.
  Result<cv::Mat> Expose(int camera_index, const cv::Mat3f& radiance,
                         const RenderOptions& options) const;

 private:
  struct Impl;
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
