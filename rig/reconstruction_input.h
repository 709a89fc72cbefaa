// The reconstruction's input from a calibrated capture folder (design.md
// sections 4-6): every view that calibration.json solved, with its frame,
// its camera's solved lens model, cam_from_object (the turntable frame in
// turntable mode, the box frame in free mode) and the calibration box's
// projected outline as a region that holds no hair.
#pragma once

#include <string>
#include <vector>

#include "core/head_spec.h"
#include "reconstruction/views.h"

namespace hairrig {

// Errors name the file: no calibration (run `hairrig calibrate` first), a
// damaged calibration.json or rig.yaml. A view the calibration did not solve
// or whose frame is missing or outside the capture folder is listed in
// `left_out` with the reason; the rest are returned.
Result<ReconstructionInput> LoadCaptureReconstructionInput(const std::string& capture_dir);

// Keeps the views with the listed ids, in the listed order (all when `ids` is
// empty). InvalidArgument naming an id that is not among the usable views.
Status SelectViews(const std::vector<int>& ids, ReconstructionInput* input);

// The subject's head for the strands, in the turntable frame: the head file
// `head_file` when given (core/head_config.h), else the `head:` of the
// capture's rig.yaml snapshot. `source` says which, for reports. NotFound
// naming both when there is neither (the rig config's `head:` or --head FILE).
struct SubjectHead {
  HeadSpec spec;
  std::string source;
};
Result<SubjectHead> LoadCaptureHead(const std::string& capture_dir, const std::string& head_file);

}  // namespace hairrig
