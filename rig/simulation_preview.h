// Pictures of strands on a head, for `hairrig simulate`'s previews. The
// drawing is plugged in by whoever links a renderer (the simulated rig
// registers its own, sim_rig/sim_rig.h), so that the dynamics run without it.
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

#include "core/head_spec.h"
#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

class StrandPreviewer {
 public:
  virtual ~StrandPreviewer() = default;
  // `strands` in the head's frame (mm); a BGR image of them on the head.
  virtual Result<cv::Mat> Draw(const StrandSet& strands) = 0;
};

// Builds a previewer from a scene file (its first camera, lights and
// backdrop) with `head` in place of the scene's own head.
using StrandPreviewerFactory = std::function<Result<std::unique_ptr<StrandPreviewer>>(
    const std::string& scene_file, const HeadSpec& head)>;

// The factory MakeStrandPreviewer uses; a later registration replaces an
// earlier one. Thread-safe.
void RegisterStrandPreviewer(StrandPreviewerFactory factory);

// FailedPrecondition when no previewer is registered (the caller then asks
// for no previews); otherwise the factory's result.
Result<std::unique_ptr<StrandPreviewer>> MakeStrandPreviewer(const std::string& scene_file,
                                                             const HeadSpec& head);

}  // namespace hairrig
