// Renders what a simulated camera sees: backdrop, head, calibration box with
// its AprilTags, and the hair, through the camera's lens distortion, exposure
// and sensor noise.
//
// Geometry is exact where calibration depends on it: the box is ray-cast per
// pixel through the inverse of the lens model (no image warping), and pixels on
// an edge are integrated with 8 x 8 stratified samples, so tag corners land
// where the camera model projects them. Strands are anti-aliased lines shaded
// with Kajiya-Kay against the two LED panels, so orientation filters see their
// direction. All panels off gives a dark frame (noise only).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "core/status.h"
#include "core/strands.h"
#include "sim_hw/scene.h"

namespace hairrig {

struct RenderOptions {
  std::vector<double> light_levels;  // one per scene light, 0..1; empty = all on
  double exposure_s = 0;             // 0 = the camera's nominal exposure
  double gain_db = 0;
  bool noise = true;
  uint64_t noise_seed = 0;           // same seed, same noise
  bool draw_hair = true;
};

// Ground truth of one tag in one rendered view.
struct TagTruth {
  int id = -1;
  std::array<Eigen::Vector2d, 4> corners_px;  // projections, libapriltag corner order
  double facing_deg = 0;  // elevation of the viewing ray above the face plane; <= 0: back-facing
  bool in_image = false;  // all corners at least 4 px inside the image
  bool unoccluded = false;  // no head or hair over any part of the printed tag
};

struct RenderedView {
  cv::Mat image;  // CV_8UC3, BGR
  std::vector<TagTruth> tags;
};

class Renderer {
 public:
  // Generates the wig and precomputes per-camera ray tables. Keeps a copy of `scene`.
  static Result<std::unique_ptr<Renderer>> Create(const Scene& scene);
  ~Renderer();

  const Scene& scene() const;
  const StrandSet& strands_turntable_mm() const;  // the wig, turntable frame
  // Replaces the wig (turntable frame, mm), e.g. with a simulated frame of it.
  // Not safe while another thread renders.
  void SetStrands(StrandSet strands_turntable_mm);

  // OutOfRange for a camera index outside the scene; InvalidArgument for light
  // levels of the wrong count or outside 0..1. Thread-safe (const).
  Result<RenderedView> Render(int camera_index, double turntable_deg, const RenderOptions& options) const;

 private:
  struct Impl;
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
