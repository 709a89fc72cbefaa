// Pictures of strand models. A turntable preview: each model drawn as lines in
// orthographic views from a few azimuths about the turntable axis (+z up),
// coloured by the strand's direction (red x, green y, blue z of |d|), one row
// per model, so a reconstruction can be shown beside the ground truth; edges
// are drawn far to near and darkened with distance from the viewer.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "reconstruction/views.h"

namespace hairrig {

struct StrandPreviewOptions {
  std::vector<double> azimuths_deg = {0, 90, 180, 270};  // finite
  int view_px = 360;                                     // each view is view_px x view_px, 16..4096
  int max_strands = 6000;  // drawn per model (evenly chosen), at least 1

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

// Rows share one scale and centre (the union of the models' bounds). An
// empty model gives an empty row with its label. InvalidArgument for bad
// options (StrandPreviewOptions::Check).
Result<cv::Mat> RenderStrandPreview(const std::vector<const StrandSet*>& models,
                                    const std::vector<std::string>& labels,
                                    const StrandPreviewOptions& options);

struct StrandOverlayOptions {
  int view_px = 480;       // each view, cropped to the strands, is scaled to this width (16..4096)
  int max_strands = 1500;  // drawn (evenly chosen), at least 1
  double opacity = 0.7;    // of the strand lines over the image, in [0, 1]

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

// The strands projected into the given views (each view's image with its lens
// model and pose; the strands in the views' object frame), side by side:
// a check that the model sits on the captured hair. Each view is cropped to
// a square about the strands it shows (grown by a fifth on every side). Strand vertices behind a
// camera are not drawn. Errors name an image that cannot be read, or the
// field of bad options (StrandOverlayOptions::Check).
Result<cv::Mat> RenderStrandsOverViews(const std::vector<ReconstructionView>& views,
                                       const StrandSet& strands,
                                       const StrandOverlayOptions& options);

}  // namespace hairrig
