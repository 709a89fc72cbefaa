#include "rig/reconstruction_input.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include "calibration/calibration_io.h"
#include "core/calib_box.h"
#include "core/head_config.h"
#include "reconstruction/hair_segmentation.h"
#include "rig/capture_calibration_input.h"
#include "rig/manifest_frames.h"

namespace hairrig {

namespace fs = std::filesystem;

namespace {

// The capture's frames by file name (as calibration.json names them), each
// checked against its manifest record.
Result<std::map<std::string, ManifestFrame>> CheckedFrames(const std::string& capture_dir) {
  HR_ASSIGN_OR_RETURN(std::vector<ManifestFrame> frames, ReadManifestFrames(capture_dir));
  HR_RETURN_IF_ERROR(VerifyManifestFrames(capture_dir, &frames));
  std::map<std::string, ManifestFrame> by_file;
  for (ManifestFrame& frame : frames) by_file.emplace(frame.file, std::move(frame));
  return by_file;
}

// Why the calibrated view's frame (`file`, relative to the capture folder)
// cannot be used, naming <capture>/<file>; "" when it can.
std::string FrameProblem(const fs::path& capture,
                         const std::map<std::string, ManifestFrame>& frames,
                         const std::string& file) {
  const auto frame = frames.find(file);
  if (frame == frames.end())
    return (capture / file).string() +
           ": no manifest.json record vouches for it; calibrate the capture again";
  return frame->second.unusable;
}

// FailedPrecondition naming the capture and the first views left out, with why.
Status TooFewViews(const std::string& capture_dir, const ReconstructionInput& input) {
  constexpr size_t kShown = 3;
  std::string message = capture_dir + ": only " + std::to_string(input.views.size()) +
                        " view(s) can be used, the reconstruction needs " +
                        std::to_string(kMinStereoViews);
  for (size_t i = 0; i < input.left_out.size() && i < kShown; ++i)
    message += (i == 0 ? "; left out: " : "; ") + input.left_out[i];
  if (input.left_out.size() > kShown)
    message += "; and " + std::to_string(input.left_out.size() - kShown) + " more";
  return FailedPrecondition(message);
}

}  // namespace

Result<ReconstructionInput> LoadCaptureReconstructionInput(const std::string& capture_dir) {
  const fs::path capture = fs::path(capture_dir).lexically_normal();
  const std::string calibration_file = (capture / "calibration" / "calibration.json").string();
  HR_ASSIGN_OR_RETURN(const StoredCalibration calibration, ReadCalibration(calibration_file));
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(capture_dir));
  HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
  HR_ASSIGN_OR_RETURN(const auto frames, CheckedFrames(capture_dir));
  const CalibBox& box = section.box;
  const std::array<Eigen::Vector3d, 8> corners = BoxCornerPoints(0.5 * box.size_mm);
  const std::vector<Eigen::Vector3d> box_corners(corners.begin(), corners.end());

  ReconstructionInput input;
  input.object_frame = calibration.mode == "turntable" ? "turntable" : "box";
  input.object_from_box =
      calibration.mode == "turntable" ? calibration.turntable_from_box : Rigid3d();
  for (const StoredCalibration::View& view : calibration.views) {
    const std::string name = fs::path(view.frame).stem().string();
    const StoredCalibration::Camera& camera = calibration.cameras[static_cast<size_t>(view.camera)];
    if (!view.solved || !camera.solved) {
      const std::string why =
          !camera.solved ? "camera " + camera.name + " was not calibrated" : view.failure;
      input.left_out.push_back(name + ": the calibration failed (" + why + ")");
      continue;
    }
    const std::string problem = FrameProblem(capture, frames, view.frame);
    if (!problem.empty()) {
      input.left_out.push_back(name + ": " + problem);
      continue;
    }
    ReconstructionView v;
    v.id = view.view;
    v.name = name;
    v.image_path = frames.at(view.frame).path;
    v.camera = camera.intrinsics;
    v.cam_from_object = view.cam_from_object;
    const std::vector<cv::Point2f> outline =
        ProjectedOutline(camera.intrinsics, view.cam_from_box, box_corners);
    if (!outline.empty()) v.not_hair_px.push_back(outline);
    input.views.push_back(std::move(v));
  }
  if (input.views.size() < kMinStereoViews) return TooFewViews(capture_dir, input);
  return input;
}

namespace {

Result<SubjectHead> FitSubjectHead(const SubjectHeadRequest& r) {
  if (r.views == nullptr || r.reconstruction_dir.empty())
    return InvalidArgument(
        "a head fit needs the views and the reconstruction folder their labels are in; give the "
        "subject's head with --head FILE instead");
  HeadFitOptions options;
  options.threads = r.threads;
  SubjectHead head;
  HR_ASSIGN_OR_RETURN(head.fit, FitHeadToReconstruction(*r.views, r.reconstruction_dir, options));
  head.spec = head.fit->head;
  const std::string path = r.reconstruction_dir + "/head.yaml";
  HR_RETURN_IF_ERROR(WriteHeadFile(path, head.spec));
  head.source = "fitted to the views' skin, " + path;
  return head;
}

}  // namespace

Status CheckColmapHead(const std::string& head_file) {
  if (!head_file.empty()) return Status::Ok();
  return InvalidArgument(
      "strands from a COLMAP model need --head FILE (the head in the model's frame), or --head "
      "fit when the model's frame is in mm with +z up");
}

Result<SubjectHead> ResolveSubjectHead(const SubjectHeadRequest& r) {
  if (r.head_file == kFittedHead) return FitSubjectHead(r);
  SubjectHead head;
  if (!r.head_file.empty()) {
    HR_ASSIGN_OR_RETURN(head.spec, LoadHeadFile(r.head_file));
    head.source = r.head_file;
    return head;
  }
  if (r.capture_dir.empty()) return CheckColmapHead(r.head_file);
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(r.capture_dir));
  if (!config.head) {
    Result<SubjectHead> fitted = FitSubjectHead(r);
    if (!fitted.ok())
      return fitted.status().WithContext(r.capture_dir +
                                         "/rig.yaml has no head:, and fitting one failed");
    return fitted;
  }
  head.spec = *config.head;
  head.source = r.capture_dir + "/rig.yaml";
  return head;
}

Status SelectViews(const std::vector<int>& ids, ReconstructionInput* input) {
  if (ids.empty()) return Status::Ok();
  std::vector<ReconstructionView> kept;
  for (int id : ids) {
    const auto it = std::find_if(input->views.begin(), input->views.end(),
                                 [id](const ReconstructionView& v) { return v.id == id; });
    if (it == input->views.end())
      return InvalidArgument("--views: view " + std::to_string(id) + " is not usable here");
    kept.push_back(*it);
  }
  input->views = std::move(kept);
  return Status::Ok();
}

}  // namespace hairrig
