// The reconstruction's input from a calibrated capture folder (docs/design.md
// sections 4-6): every view that calibration.json solved, with its frame,
// its camera's solved lens model, cam_from_object (the turntable frame in
// turntable mode, the box frame in free mode) and the calibration box's
// projected outline as a region that holds no hair.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/head_spec.h"
#include "reconstruction/head_fit.h"
#include "reconstruction/views.h"

namespace hairrig {

// Each view's frame is checked against its manifest.json record before it is
// used (rig/manifest_frames.h), and its image_path is the file that was
// checked (its symlinks resolved). A view the calibration did not solve, or whose
// frame no manifest record vouches for or does not verify (missing, changed:
// another size or SHA-256, leading outside the capture folder), is listed in
// `left_out` as "<view name>: <why>", the why naming <capture>/<file>; the rest are
// returned. Errors name the file: no calibration (run `hairrig calibrate`
// first), a damaged calibration.json, manifest.json or rig.yaml, a frames/
// folder leading outside the capture folder (FailedPrecondition), fewer than
// two usable views (FailedPrecondition naming the first views left out).
Result<ReconstructionInput> LoadCaptureReconstructionInput(const std::string& capture_dir);

// Keeps the views with the listed ids, in the listed order (all when `ids` is
// empty). InvalidArgument naming an id that is not among the usable views.
Status SelectViews(const std::vector<int>& ids, ReconstructionInput* input);

// The value of --head that asks for a head fitted to the views even where
// the rig config gives one.
inline constexpr char kFittedHead[] = "fit";

// The subject's head for the strands, in the object frame (the turntable
// frame for a capture), and where it came from:
//  - `head_file` naming a file: that head file (core/head_config.h);
//  - `head_file` kFittedHead, or empty where capture_dir/rig.yaml has no
//    `head:`: an ellipsoid and scalp fitted to the views' labels in
//    reconstruction_dir/masks
//    (reconstruction/head_fit.h), written to reconstruction_dir/head.yaml
//    so that reconstruct --head and simulate --head take it;
//  - empty: the `head:` of capture_dir/rig.yaml; InvalidArgument without a
//    capture_dir (a COLMAP model's frame need not be in mm with +z up, as the
//    fit assumes).
// `source` says which, for reports. Errors: a head file's, a damaged
// rig.yaml, or the fit's (no labels: run the points stage; no skin seen:
// give --head FILE).
struct SubjectHead {
  HeadSpec spec;
  std::string source;
  std::optional<HeadFitSummary> fit;  // set when the head was fitted
};
struct SubjectHeadRequest {
  std::string head_file;
  std::string capture_dir;  // empty for a COLMAP model
  std::string reconstruction_dir;
  const std::vector<ReconstructionView>* views = nullptr;  // for a fit
  int threads = 2;
};
Result<SubjectHead> ResolveSubjectHead(const SubjectHeadRequest& request);

// Ok when a COLMAP model's strands have a head to go on (`head_file` a file
// or kFittedHead); else InvalidArgument saying which --head to give.
Status CheckColmapHead(const std::string& head_file);

}  // namespace hairrig
