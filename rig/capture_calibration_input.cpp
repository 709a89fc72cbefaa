#include "rig/capture_calibration_input.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include "calibration/calibration_io.h"
#include "core/image_file.h"
#include "rig/capture_dataset.h"
#include "rig/manifest_frames.h"
#include "rig/rig_config.h"

namespace hairrig {

namespace fs = std::filesystem;

namespace {

// The rig config's nominal intrinsics of one camera (calibration.cameras.<name>).
CameraIntrinsics ReadNominalIntrinsics(const ConfigNode& k) {
  k.AllowOnlyKeys({"fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3"});
  const NumberRange coefficient{-1e3, 1e3};
  CameraIntrinsics intrinsics;
  intrinsics.fx_px = k.Number("fx_px", {.min = 1, .max = 1e6});
  intrinsics.fy_px = k.Number("fy_px", {.min = 1, .max = 1e6});
  intrinsics.cx_px = k.Number("cx_px", kPixelRange);
  intrinsics.cy_px = k.Number("cy_px", kPixelRange);
  intrinsics.k1 = k.Number("k1", 0.0, coefficient);
  intrinsics.k2 = k.Number("k2", 0.0, coefficient);
  intrinsics.p1 = k.Number("p1", 0.0, coefficient);
  intrinsics.p2 = k.Number("p2", 0.0, coefficient);
  intrinsics.k3 = k.Number("k3", 0.0, coefficient);
  return intrinsics;  // the size is filled in from the frames
}

// Cameras from the config snapshot, each with its image size from its first frame.
Status AddCameras(const RigConfig& config, CaptureCalibrationInput* input,
                  std::map<std::string, int>* by_serial) {
  const ConfigNode nominal = config.root.OptionalChild("calibration").OptionalChild("cameras");
  std::string names;
  for (const ConfigNode& cam : config.root.Child("devices").Items("cameras")) {
    CalibrationCamera camera;
    camera.name = cam.String("name");
    camera.serial = cam.String("serial");
    names += (names.empty() ? "" : ", ") + camera.name;
    if (nominal.IsMap() && nominal.Has(camera.name))
      camera.nominal = ReadNominalIntrinsics(nominal.Child(camera.name));
    (*by_serial)[camera.serial] = static_cast<int>(input->cameras.size());
    input->cameras.push_back(camera);
  }
  for (const std::string& name : nominal.Keys()) {
    bool known = false;
    for (const CalibrationCamera& camera : input->cameras) known = known || camera.name == name;
    if (known) continue;
    nominal.Fail(name, "no camera named " + QuotedExcerpt(name) +
                           " in the devices section (cameras: " + names + ")");
  }
  return config.root.status();
}

// The manifest's frames, read by ReadManifestFrames: every camera checked
// against rig.yaml before VerifyManifestFrames reads a file; a frame whose file
// does not verify is marked unusable and named in the calibration's report.
Status AddFrames(const std::string& capture_dir, std::vector<ManifestFrame> stored,
                 const std::map<std::string, int>& by_serial, CaptureCalibrationInput* input) {
  const std::string config = (fs::path(capture_dir) / "rig.yaml").string();
  for (const ManifestFrame& f : stored) {
    if (by_serial.count(f.serial) == 0)
      return CorruptData(f.serial_field + ": camera " + f.serial + " is not among the cameras of " +
                         config + "; add the camera to rig.yaml or restore the capture's rig.yaml");
  }
  HR_RETURN_IF_ERROR(VerifyManifestFrames(capture_dir, &stored));
  for (const ManifestFrame& f : stored) {
    CalibrationFrame frame;
    frame.view = f.view;
    frame.stop = f.stop;
    frame.turntable_deg = f.angle_measured_deg;
    frame.name = f.file;
    frame.path = f.path;
    frame.camera = by_serial.at(f.serial);
    frame.unusable = f.unusable;
    input->frames.push_back(std::move(frame));
  }
  return Status::Ok();
}

// Image sizes from each camera's first usable frame whose header
// (core/image_file.h, read without decoding) gives a size within
// kMaxImagePixels. A frame skipped here is left to the calibration, which
// reads it through ReadImageFile and names it with the reason.
void FillImageSizes(CaptureCalibrationInput* input) {
  for (size_t c = 0; c < input->cameras.size(); ++c) {
    CalibrationCamera& camera = input->cameras[c];
    for (const CalibrationFrame& frame : input->frames) {
      if (frame.camera != static_cast<int>(c) || !frame.unusable.empty()) continue;
      const Result<ImageHeader> header = ReadImageHeader(frame.path);
      if (!header.ok() || !CheckImageSize(*header, frame.path).ok()) continue;
      // Within kMaxImagePixels, each side is well inside an int.
      camera.width_px = static_cast<int>(header->width_px);
      camera.height_px = static_cast<int>(header->height_px);
      break;
    }
    if (camera.nominal) {
      camera.nominal->width_px = camera.width_px;
      camera.nominal->height_px = camera.height_px;
    }
  }
}

}  // namespace

Result<CalibrationSection> ReadCalibrationSection(const RigConfig& config) {
  const ConfigNode section = config.root.Child("calibration");
  section.AllowOnlyKeys({"box", "box_height_mm", "box_yaw_deg", "cameras"});
  const std::string box_file = section.String("box");
  CalibrationSection out;
  out.box_height_mm = section.Number("box_height_mm", kPositionRangeMm);
  out.box_yaw_deg = section.Number("box_yaw_deg", 0.0, {.min = -360, .max = 360});
  HR_RETURN_IF_ERROR(config.root.status());
  out.box_file = (fs::path(config.relative_to) / box_file).lexically_normal().string();
  HR_ASSIGN_OR_RETURN(out.box, LoadCalibBox(out.box_file));
  return out;
}

Status CheckCalibrationSection(const RigConfig& config) {
  if (!config.root.Has("calibration")) return Status::Ok();
  return ReadCalibrationSection(config).status();
}

Result<RigConfig> LoadCaptureRigConfig(const std::string& capture_dir) {
  HR_ASSIGN_OR_RETURN(const CaptureMetadata metadata, ReadCaptureMetadata(capture_dir));
  return LoadRigConfig((fs::path(capture_dir) / "rig.yaml").string(), metadata.config_dir,
                       UnclaimedSections::kIgnore);
}

Result<CaptureCalibrationInput> LoadCaptureCalibrationInput(const std::string& capture_dir) {
  HR_ASSIGN_OR_RETURN(std::vector<ManifestFrame> frames, ReadManifestFrames(capture_dir));
  HR_ASSIGN_OR_RETURN(RigConfig config, LoadCaptureRigConfig(capture_dir));
  CaptureCalibrationInput input;
  HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
  input.box = section.box;
  input.box_source = section.box_file;
  input.box_height_mm = section.box_height_mm;
  input.box_yaw_deg = section.box_yaw_deg;
  std::map<std::string, int> by_serial;
  HR_RETURN_IF_ERROR(AddCameras(config, &input, &by_serial));
  HR_RETURN_IF_ERROR(AddFrames(capture_dir, std::move(frames), by_serial, &input));
  FillImageSizes(&input);
  return input;
}

Status ApplyIntrinsicsPriors(const std::vector<std::string>& prior_paths,
                             CaptureCalibrationInput* input) {
  std::map<std::string, IntrinsicsPrior> by_serial;
  for (const std::string& path : prior_paths) {
    HR_ASSIGN_OR_RETURN(std::vector<IntrinsicsPrior> priors, ReadIntrinsicsPriors(path));
    for (IntrinsicsPrior& prior : priors) by_serial[prior.serial] = std::move(prior);
  }
  for (CalibrationCamera& camera : input->cameras) {
    const auto match = by_serial.find(camera.serial);
    if (match == by_serial.end())
      return InvalidArgument(
          "--intrinsics: no file gives camera " + camera.serial +
          "; calibrate it with `hairrig calibrate-intrinsics` and pass that file too");
    const IntrinsicsPrior& prior = match->second;
    if (prior.intrinsics.width_px != camera.width_px ||
        prior.intrinsics.height_px != camera.height_px)
      return InvalidArgument("--intrinsics " + prior.source + ": camera " + camera.serial +
                             " was calibrated at " + std::to_string(prior.intrinsics.width_px) +
                             " x " + std::to_string(prior.intrinsics.height_px) +
                             " px, the capture's frames are " + std::to_string(camera.width_px) +
                             " x " + std::to_string(camera.height_px));
    camera.nominal = prior.intrinsics;
    camera.nominal_stddev = prior.stddev;
    camera.prior_source = prior.source;
  }
  return Status::Ok();
}

}  // namespace hairrig
