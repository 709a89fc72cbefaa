// Test helper: one view of a scene rendered (noise seeded by the view index),
// its tags detected and matched to the scene's box. Header-only, for tests/.
#pragma once

#include "calibration/view_pose.h"
#include "sim_hw/renderer.h"

namespace hairrig {

// The wig is not drawn: the box hangs above the head, so no hair covers a tag
// (the default scene's views give the same tags either way), and the hair is
// most of a view's render time.
inline Result<ViewObservations> RenderedObservations(const Renderer& renderer,
                                                     TagDetector& detector, int camera, int stop) {
  const Scene& scene = renderer.scene();
  RenderOptions options;
  options.draw_hair = false;
  options.noise_seed =
      static_cast<uint64_t>(stop * static_cast<int>(scene.cameras.size()) + camera);
  HR_ASSIGN_OR_RETURN(RenderedView rendered,
                      renderer.Render(camera, scene.StopAngleDeg(stop), options));
  HR_ASSIGN_OR_RETURN(std::vector<TagDetection> detections, detector.Detect(rendered.image));
  return MatchToBox(detections, scene.drawn_box);
}

}  // namespace hairrig
