// A turntable preview of strand models: each model drawn as lines in
// orthographic views from a few azimuths about the turntable axis (+z up),
// coloured by the strand's direction (red x, green y, blue z of |d|), one row
// per model, so a reconstruction can be shown beside the ground truth.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "core/strands.h"

namespace hairrig {

struct StrandPreviewOptions {
  std::vector<double> azimuths_deg = {0, 90, 180, 270};
  int view_px = 360;     // each view is view_px x view_px
  int max_strands = 6000; // drawn per model (evenly chosen)
};

// Rows share one scale and centre (the union of the models' bounds). An
// empty model gives an empty row with its label.
cv::Mat RenderStrandPreview(const std::vector<const StrandSet*>& models, const std::vector<std::string>& labels,
                            const StrandPreviewOptions& options);

}  // namespace hairrig
