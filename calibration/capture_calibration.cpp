#include "calibration/capture_calibration.h"

#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "calibration/intrinsics_from_views.h"
#include "calibration/turntable_axis.h"
#include "core/image_file.h"
#include "core/parallel.h"

namespace hairrig {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A prior is only valid at the image size it was calibrated at.
Status CheckPriorImageSize(const CalibrationCamera& camera,
                           const CaptureCalibrationOptions& options) {
  const CameraIntrinsics& prior = *camera.nominal;
  if (!options.fix_intrinsics || camera.width_px <= 0 || camera.height_px <= 0 ||
      (prior.width_px == camera.width_px && prior.height_px == camera.height_px))
    return Status::Ok();
  const std::string from = camera.prior_source.empty() ? "" : " (" + camera.prior_source + ")";
  return InvalidArgument(
      "calibration: camera " + camera.name + ": the intrinsics prior" + from + " is for " +
      std::to_string(prior.width_px) + " x " + std::to_string(prior.height_px) +
      " px images, the camera's frames are " + std::to_string(camera.width_px) + " x " +
      std::to_string(camera.height_px) + "; pass the file calibrated at the frames' size");
}

Status ValidateInput(const CaptureCalibrationInput& input,
                     const CaptureCalibrationOptions& options) {
  if (input.cameras.empty()) return InvalidArgument("calibration: no camera");
  if (input.frames.empty()) return InvalidArgument("calibration: no frame to calibrate from");
  if (input.box.tags.empty()) return InvalidArgument("calibration: the box model has no tag");
  for (const CalibrationCamera& camera : input.cameras) {
    if (options.fix_intrinsics && !camera.nominal)
      return InvalidArgument("calibration: intrinsics are to be held fixed but camera " +
                             camera.name + " has no prior values");
    if (camera.nominal) {
      const Status valid = camera.nominal->Check();
      if (!valid.ok())
        return InvalidArgument("calibration: camera " + camera.name + ": " + valid.message());
      HR_RETURN_IF_ERROR(CheckPriorImageSize(camera, options));
    }
  }
  for (const CalibrationFrame& frame : input.frames) {
    if (frame.camera < 0 || frame.camera >= static_cast<int>(input.cameras.size()))
      return InvalidArgument("calibration: frame " + frame.name + " names camera " +
                             std::to_string(frame.camera) + " of " +
                             std::to_string(input.cameras.size()));
    if (!std::isfinite(frame.turntable_deg))
      return InvalidArgument("calibration: frame " + frame.name + " has no finite turntable angle");
  }
  if (options.mode == CalibrationMode::kTurntable && !std::isfinite(input.box_height_mm))
    return InvalidArgument("calibration: the box height is not a finite number");
  return Status::Ok();
}

// Step 2a: every camera's starting intrinsics.
void InitialiseIntrinsics(const CaptureCalibrationInput& input,
                          const CaptureCalibrationOptions& options,
                          const std::vector<ViewObservations>& observations,
                          CaptureCalibration* out) {
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    const CalibrationCamera& camera = input.cameras[c];
    CameraCalibration& result = out->cameras[c];
    if (camera.nominal) {
      result.initial = *camera.nominal;
      result.intrinsics_source = options.fix_intrinsics ? "prior" : "nominal";
      result.solved = true;
      continue;
    }
    std::vector<const ViewObservations*> views;
    for (size_t f = 0; f < input.frames.size(); ++f)
      if (input.frames[f].camera == static_cast<int>(c)) views.push_back(&observations[f]);
    auto solved = SolveIntrinsicsFromViews(views, input.box, camera.width_px, camera.height_px);
    if (!solved.ok()) {
      result.failure = solved.status().message();
      continue;
    }
    result.initial = solved->intrinsics;
    result.intrinsics_source = "views";
    result.solved = true;
  }
}

// Step 2b: a pose per frame from its camera's starting intrinsics.
void InitialisePoses(const CaptureCalibrationInput& input, const CaptureCalibrationOptions& options,
                     const std::vector<ViewObservations>& observations, CaptureCalibration* out) {
  // With the box refined, a tag is judged against the box it may be.
  ViewPoseOptions pose_options = options.pose;
  double largest_tag_mm = 0;
  for (const BoxTag& tag : input.box.tags) largest_tag_mm = std::max(largest_tag_mm, tag.size_mm);
  pose_options.box_tolerance_mm =
      std::max(pose_options.box_tolerance_mm,
               options.box_tolerance.CornerMm(largest_tag_mm, 0.5 * input.box.size_mm.maxCoeff()));
  for (size_t f = 0; f < input.frames.size(); ++f) {
    FrameCalibration& frame = out->frames[f];
    if (!frame.failure.empty()) continue;  // unreadable
    const CameraCalibration& camera = out->cameras[static_cast<size_t>(input.frames[f].camera)];
    frame.tags = observations[f].tags;
    frame.rejected = observations[f].rejected;
    if (!camera.solved) {
      frame.failure = "camera " + input.cameras[static_cast<size_t>(input.frames[f].camera)].name +
                      " has no starting intrinsics";
      continue;
    }
    auto pose = EstimateViewPose(observations[f], camera.initial, pose_options);
    if (!pose.ok()) {
      frame.failure = pose.status().message();
      continue;
    }
    frame.rejected = pose->rejected;
    frame.cam_from_box_init = pose->cam_from_box;
    frame.init_rms_px = pose->rms_px;
    frame.solved = true;
  }
}

struct SolveMap {
  std::vector<int> camera_of;    // bundle-adjustment camera -> input camera
  std::vector<int> ba_camera;    // input camera -> bundle-adjustment camera, -1 if left out
  std::vector<size_t> frame_of;  // bundle-adjustment view -> input frame
};

// The bundle adjustment's input from the solved frames; cameras without one are named and left out.
BundleAdjustmentInput BuildAdjustmentInput(const CaptureCalibrationInput& input,
                                           CaptureCalibration* out, SolveMap* map) {
  BundleAdjustmentInput ba;
  map->ba_camera.assign(input.cameras.size(), -1);
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    CameraCalibration& camera = out->cameras[c];
    bool has_view = false;
    for (size_t f = 0; f < input.frames.size(); ++f)
      has_view |= out->frames[f].solved && input.frames[f].camera == static_cast<int>(c);
    if (camera.solved && !has_view) {
      camera.solved = false;
      camera.failure = "no view of this camera could be solved";
    }
    if (!camera.solved) continue;
    map->ba_camera[c] = static_cast<int>(ba.cameras.size());
    map->camera_of.push_back(static_cast<int>(c));
    ba.cameras.push_back(camera.initial);
    ba.prior_stddev.push_back(input.cameras[c].nominal_stddev);
  }
  for (size_t f = 0; f < input.frames.size(); ++f) {
    const FrameCalibration& frame = out->frames[f];
    if (!frame.solved) continue;
    CalibrationView view;
    view.camera = map->ba_camera[static_cast<size_t>(input.frames[f].camera)];
    view.stop = input.frames[f].stop;
    view.turntable_deg = input.frames[f].turntable_deg;
    view.tags = frame.tags;
    view.cam_from_box_init = frame.cam_from_box_init;
    ba.views.push_back(std::move(view));
    map->frame_of.push_back(f);
  }
  return ba;
}

void CopySolution(const BundleAdjustmentResult& solution, const SolveMap& map,
                  CaptureCalibration* out) {
  for (size_t k = 0; k < map.camera_of.size(); ++k) {
    CameraCalibration& camera = out->cameras[static_cast<size_t>(map.camera_of[k])];
    camera.intrinsics = solution.cameras[k];
    if (k < solution.intrinsics_stddev.size())
      camera.intrinsics_stddev = solution.intrinsics_stddev[k];
    if (k < solution.cam_from_world.size()) camera.cam_from_world = solution.cam_from_world[k];
  }
  for (size_t v = 0; v < map.frame_of.size(); ++v) {
    FrameCalibration& frame = out->frames[map.frame_of[v]];
    frame.cam_from_box = solution.cam_from_box[v];
    frame.rms_px = solution.view_rms_px[v];
    frame.uncertainty = solution.view_uncertainty[v];
  }
  out->turntable_from_box = solution.turntable_from_box;
  out->rms_px = solution.rms_px;
  out->residual_sigma_px = solution.residual_sigma_px;
  out->iterations = solution.iterations;
  out->converged = solution.converged;
}

// Step 4: the bundle adjustment again with free intrinsics, from the solved
// poses and the priors, and each camera's prior tested against the
// intrinsics it gives.
void CheckPriors(const BundleAdjustmentInput& ba, const BundleAdjustmentResult& solution,
                 const BundleAdjustmentOptions& ba_options, const SolveMap& map,
                 const CaptureCalibrationOptions& options, CaptureCalibration* out) {
  BundleAdjustmentInput views_only = ba;
  views_only.prior_stddev.clear();
  for (size_t v = 0; v < views_only.views.size(); ++v)
    views_only.views[v].cam_from_box_init = solution.cam_from_box[v];
  if (ba_options.mode == CalibrationMode::kTurntable)
    views_only.turntable_from_box_init = solution.turntable_from_box;
  BundleAdjustmentOptions free_options = ba_options;
  free_options.fix_intrinsics = false;
  const auto solved = RunBundleAdjustment(views_only, free_options);
  for (size_t k = 0; k < map.camera_of.size(); ++k) {
    PriorCheck& check = out->cameras[static_cast<size_t>(map.camera_of[k])].prior_check;
    if (!solved.ok()) {
      check.prior = ba.cameras[k];
      check.not_tested = "the views alone cannot be solved (" + solved.status().message() + ")";
      continue;
    }
    check = CheckIntrinsicsPrior(ba.cameras[k], ba.prior_stddev[k], solved->cameras[k],
                                 solved->intrinsics_covariance[k], options.prior_check);
  }
}

// The box check: the views solved once more, from the solution, with the box
// refined when the solution took it as given and as given when it was refined;
// both sigmas and the refined solve's moves into `out`.
void CheckBox(const BundleAdjustmentInput& ba, const BundleAdjustmentResult& solution,
              const BundleAdjustmentOptions& ba_options, const CalibBox& given,
              CaptureCalibration* out) {
  out->box_refined = solution.box_refined;
  out->box_tolerance = ba_options.box_tolerance;
  out->box_as_built = solution.box_refined ? solution.box : given;
  BundleAdjustmentInput again = ba;
  for (size_t v = 0; v < again.views.size(); ++v)
    again.views[v].cam_from_box_init = solution.cam_from_box[v];
  again.turntable_from_box_init = solution.turntable_from_box;
  for (size_t c = 0; c < again.cameras.size(); ++c) again.cameras[c] = solution.cameras[c];
  BundleAdjustmentOptions other = ba_options;
  other.box_tolerance = solution.box_refined ? BoxTolerance{} : kHandBuiltBoxTolerance;
  const auto compared = RunBundleAdjustment(again, other);
  const BundleAdjustmentResult* refined = solution.box_refined ? &solution : nullptr;
  if (compared.ok() && !solution.box_refined) refined = &*compared;
  const double other_sigma = compared.ok() ? compared->residual_sigma_px : NAN;
  out->sigma_box_as_given_px = solution.box_refined ? other_sigma : solution.residual_sigma_px;
  out->sigma_box_refined_px = solution.box_refined ? solution.residual_sigma_px : other_sigma;
  if (refined != nullptr) {
    out->tag_moves = refined->tag_moves;
    out->face_moves = refined->face_moves;
  }
}

// Observations matched earlier (while the frames landed, maybe to another box
// file) with their corners placed on `box`; a tag it lacks is rejected.
ViewObservations PlaceOnBox(const ViewObservations& matched, const CalibBox& box) {
  ViewObservations out;
  out.rejected = matched.rejected;
  for (const TagObservation& tag : matched.tags) {
    const BoxTag* on_box = box.FindTag(tag.id);
    if (on_box == nullptr) {
      out.rejected.push_back({tag.id, "not on the calibration box given"});
      continue;
    }
    out.tags.push_back({tag.id, tag.corners_px, on_box->corners_box_mm});
  }
  return out;
}

// The frames' tag corners on the box as refined, so that what is drawn and
// exported from them matches the solve.
void UseRefinedCorners(CaptureCalibration* out) {
  for (FrameCalibration& frame : out->frames) {
    for (TagObservation& tag : frame.tags) {
      const BoxTag* refined = out->box_as_built.FindTag(tag.id);
      if (refined != nullptr) tag.corners_box_mm = refined->corners_box_mm;
    }
  }
}

}  // namespace

std::vector<int> TagsUsed(const CaptureCalibration& result) {
  std::set<int> ids;
  for (const FrameCalibration& frame : result.frames)
    if (frame.solved)
      for (const TagObservation& tag : frame.tags) ids.insert(tag.id);
  return {ids.begin(), ids.end()};
}

std::vector<ViewObservations> DetectFrames(const std::vector<CalibrationFrame>& frames,
                                           const CalibBox& box, const TagDetectorOptions& detector,
                                           int threads, std::vector<std::string>* failures) {
  std::vector<ViewObservations> observations(frames.size());
  failures->assign(frames.size(), "");
  ParallelFor(frames.size(), threads, [&] {
    auto tag_detector = TagDetector::Create(detector);
    return [&, tag_detector = std::move(tag_detector)](size_t f) {
      if (!frames[f].unusable.empty()) {
        (*failures)[f] = frames[f].unusable;
        return;
      }
      if (frames[f].observations) {
        observations[f] = PlaceOnBox(*frames[f].observations, box);
        return;
      }
      if (!tag_detector.ok()) {
        (*failures)[f] = tag_detector.status().message();
        return;
      }
      const Result<cv::Mat> image = ReadImageFile(frames[f].path, cv::IMREAD_GRAYSCALE);
      if (!image.ok()) {
        (*failures)[f] = image.status().message();
        return;
      }
      auto detections = (*tag_detector)->Detect(*image);
      if (!detections.ok()) {
        (*failures)[f] = frames[f].path + ": " + detections.status().message();
        return;
      }
      observations[f] = MatchToBox(*detections, box);
    };
  });
  return observations;
}

Status CaptureCalibrationOptions::Check() const {
  if (threads < 1)
    return InvalidArgument("threads must be at least 1, got " + std::to_string(threads));
  if (!(huber_px > 0) || !std::isfinite(huber_px))
    return InvalidArgument("huber_px must be a finite positive number of pixels");
  HR_RETURN_IF_ERROR(box_tolerance.Check().WithContext("box_tolerance"));
  HR_RETURN_IF_ERROR(detector.Check().WithContext("detector"));
  HR_RETURN_IF_ERROR(pose.Check().WithContext("pose"));
  return prior_check.Check().WithContext("prior_check");
}

Result<CaptureCalibration> CalibrateCapture(const CaptureCalibrationInput& input,
                                            const CaptureCalibrationOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("calibration"));
  HR_RETURN_IF_ERROR(ValidateInput(input, options));
  CaptureCalibration out;
  out.mode = options.mode;
  out.cameras.resize(input.cameras.size());
  out.frames.resize(input.frames.size());
  auto start = std::chrono::steady_clock::now();
  std::vector<std::string> unreadable;
  const std::vector<ViewObservations> observations = DetectFrames(
      input.frames, input.box, options.detector, std::max(1, options.threads), &unreadable);
  for (size_t f = 0; f < input.frames.size(); ++f) {
    out.frames[f].failure = unreadable[f];
    out.frames[f].tags_detected =
        static_cast<int>(observations[f].tags.size() + observations[f].rejected.size());
  }
  out.detect_s = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  InitialiseIntrinsics(input, options, observations, &out);
  InitialisePoses(input, options, observations, &out);
  SolveMap map;
  BundleAdjustmentInput ba = BuildAdjustmentInput(input, &out, &map);
  if (ba.cameras.empty()) {
    std::string why;
    for (size_t c = 0; c < input.cameras.size(); ++c)
      why += (why.empty() ? "" : "; ") + input.cameras[c].name + ": " + out.cameras[c].failure;
    return FailedPrecondition("calibration: no camera can be solved (" + why + ")");
  }
  if (options.mode == CalibrationMode::kTurntable) {
    auto axis = FitTurntableAxis(ba.views, input.box_height_mm, input.box_yaw_deg);
    if (!axis.ok())
      return FailedPrecondition("calibration: " + axis.status().message() +
                                "; for a capture without turntable motion use --mode free");
    ba.turntable_from_box_init = axis->turntable_from_box;
  }
  out.init_s = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  BundleAdjustmentOptions ba_options;
  ba_options.mode = options.mode;
  ba_options.fix_intrinsics = options.fix_intrinsics;
  ba_options.hard_prior = options.hard_prior;
  ba_options.huber_px = options.huber_px;
  ba_options.threads = std::max(1, options.threads);
  ba_options.box_tolerance = options.box_tolerance;
  ba.box = input.box;
  HR_ASSIGN_OR_RETURN(BundleAdjustmentResult solution, RunBundleAdjustment(ba, ba_options));
  CopySolution(solution, map, &out);
  CheckBox(ba, solution, ba_options, input.box, &out);
  if (out.box_refined) UseRefinedCorners(&out);
  out.solve_s = SecondsSince(start);

  if (options.fix_intrinsics && options.check_priors) {
    start = std::chrono::steady_clock::now();
    CheckPriors(ba, solution, ba_options, map, options, &out);
    out.prior_check_s = SecondsSince(start);
  }
  return out;
}

}  // namespace hairrig
