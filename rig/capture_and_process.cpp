#include "rig/capture_and_process.h"

#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "calibration/tag_detection_sink.h"
#include "core/capture_storage.h"
#include "core/clock.h"
#include "core/log.h"
#include "core/string_format.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"
#include "rig/safe_names.h"

namespace hairrig {

namespace {

double SecondsSince(int64_t start_ns, int64_t end_ns) {
  return static_cast<double>(end_ns - start_ns) * 1e-9;
}

Result<CalibrationAfterCapture> CalibrateAfterCapture(const std::string& dir,
                                                      const std::vector<std::string>& priors,
                                                      int threads, TagDetectionSink& sink) {
  CalibrationAfterCapture after;
  after.capture_closed_s = SecondsSince(sink.last_frame_ns(), SteadyNowNs());
  const std::map<std::string, ViewObservations> detected = sink.WaitForAll();
  after.detection_backlog_s = SecondsSince(sink.last_frame_ns(), sink.last_detected_ns());
  after.frames_detected_during_capture = static_cast<int>(detected.size());
  CalibrateFolderOptions options;
  options.prior_files = priors;
  options.calibration.threads = threads;
  options.detected = &detected;
  int64_t written_ns = 0;
  options.on_written = [&] { written_ns = SteadyNowNs(); };
  HR_ASSIGN_OR_RETURN(after.calibration, CalibrateCaptureFolder(dir, options));
  after.calibration_after_last_frame_s = SecondsSince(sink.last_frame_ns(), written_ns);
  after.delay_after_last_frame_s = SecondsSince(sink.last_frame_ns(), SteadyNowNs());
  return after;
}

// Bytes the calibration writes into a capture folder at most: calibration.json,
// the exports and the report, whose half-size residual JPEG per frame takes
// less than an eighth of the frame's file; 1 MB for the rest.
uint64_t CalibrationBytesBound(const std::string& capture_dir) {
  uint64_t frames = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(capture_dir + "/frames", ec)) {
    if (entry.is_regular_file(ec)) frames += entry.file_size(ec);
  }
  return frames / 8 + 1'000'000;
}

// Ok when the calibration's files (CalibrationBytesBound) leave the capture's
// storage.min_free_mb free on its disk: the check every file of the capture
// passed (CheckRoomOnDisk). IoError naming the folder and the limit otherwise.
Status CheckRoomForCalibration(const std::string& capture_dir, const CaptureStorage& storage) {
  HR_ASSIGN_OR_RETURN(const RigConfig config, LoadCaptureRigConfig(capture_dir));
  HR_ASSIGN_OR_RETURN(const CapturePolicies policies, ReadCapturePolicies(config.root));
  HR_ASSIGN_OR_RETURN(const uint64_t free, storage.FreeBytes(capture_dir));
  const uint64_t bytes = CalibrationBytesBound(capture_dir);
  return CheckRoomOnDisk(
      capture_dir, free, 0, bytes,
      StringPrintf("the calibration's files (up to %.1f MB)", static_cast<double>(bytes) / 1e6),
      policies.MinFreeBytes(), 0);
}

// The capture folder, and the capture's settings for RunCapture.
Result<CaptureOptions> MakeCaptureOptions(const CaptureAndProcessOptions& o) {
  CaptureOptions capture;
  capture.resume = o.resume;
  capture.out_dir = o.out_dir;
  if (!o.subject.empty()) {
    HR_ASSIGN_OR_RETURN(const std::string folder,
                        SubjectFolderName(o.folder_name.empty() ? o.subject : o.folder_name));
    std::error_code ec;
    std::filesystem::create_directories(o.out_dir, ec);
    if (ec)
      return IoError(o.out_dir + ": cannot create the folder of captures (" + ec.message() + ")");
    capture.out_dir = (std::filesystem::path(o.out_dir) / folder).string();
    capture.subject = o.subject;
  }
  capture.config_path = o.rig ? o.rig->config.path : o.config_path;
  capture.rig = o.rig;
  if (capture.config_path.empty() && !o.resume) {
    HR_ASSIGN_OR_RETURN(capture.config_path, DefaultRigConfigPath());
  }
  if (o.resume && !o.config_path.empty()) {
    LogWarning("--config is ignored with --resume: the capture's own rig.yaml snapshot is used");
  }
  capture.on_progress = o.on_progress;
  return capture;
}

// Detects the box's tags as frames land, with the box of the config the capture runs.
Result<std::unique_ptr<TagDetectionSink>> MakeDetectionSink(const CaptureOptions& capture,
                                                            int threads) {
  HR_ASSIGN_OR_RETURN(const RigConfig config, capture.resume ? LoadCaptureRigConfig(capture.out_dir)
                                                             : LoadRigConfig(capture.config_path));
  HR_ASSIGN_OR_RETURN(const CalibrationSection section, ReadCalibrationSection(config));
  return std::make_unique<TagDetectionSink>(section.box, TagDetectorOptions{}, threads);
}

std::string CaptureBriefReport(const CaptureSummary& s) {
  std::string text = StringPrintf("capture %s: %s\n", s.dir.c_str(), s.status.c_str());
  text +=
      StringPrintf("  views %d of %d (%d kept from before), %d frames, %.1f MB stored, %d faults\n",
                   s.views_completed, s.views_planned, s.views_kept, s.frames,
                   static_cast<double>(s.bytes) / 1e6, s.faults);
  text +=
      StringPrintf("  sweep %.2f s, physical lower bound %.2f s, efficiency %.3f (setup %.2f s)\n",
                   s.wall_s, s.lower_bound_s, s.efficiency, s.setup_s);
  if (!s.message.empty()) text += "  " + s.message + "\n";
  return text;
}

}  // namespace

Status CaptureAndProcessOptions::Check() const {
  if (out_dir.empty())
    return InvalidArgument("capture: out_dir (--out, the capture folder) is required");
  if (!intrinsics_files.empty() && !calibrate)
    return InvalidArgument("--intrinsics needs --calibrate");
  if (reconstruct && !calibrate) return InvalidArgument("--reconstruct needs --calibrate");
  if (threads < 1) return InvalidArgument("--threads must be at least 1");
  return Status::Ok();
}

nlohmann::json CaptureAndProcessSummary::ToJson() const {
  nlohmann::json out = capture.ToJson();
  if (calibration) {
    nlohmann::json& c = out["calibration"] = calibration->calibration.ToJson();
    c["frames_detected_during_capture"] = calibration->frames_detected_during_capture;
    c["detection_backlog_s"] = calibration->detection_backlog_s;
    c["capture_closed_s"] = calibration->capture_closed_s;
    c["calibration_after_last_frame_s"] = calibration->calibration_after_last_frame_s;
    c["delay_after_last_frame_s"] = calibration->delay_after_last_frame_s;
  }
  if (calibration_skipped) {
    out["calibration_skipped"] = {{"reason", calibration_skipped->reason},
                                  {"action", calibration_skipped->action}};
  }
  if (reconstruction) out["reconstruction"] = reconstruction->ToJson();
  return out;
}

std::string CaptureAndProcessSummary::BriefReport() const {
  std::string text = CaptureBriefReport(capture);
  if (calibration) {
    const CalibrationAfterCapture& c = *calibration;
    text += c.calibration.BriefReport();
    text += StringPrintf(
        "  after the last frame: its detection done %.2f s, capture closed (contact sheet, ground "
        "truth) %.2f s, calibration.json written %.2f s, report %.2f s (%d frames detected during "
        "the capture)\n",
        c.detection_backlog_s, c.capture_closed_s, c.calibration_after_last_frame_s,
        c.delay_after_last_frame_s, c.frames_detected_during_capture);
  }
  if (calibration_skipped) {
    text += "calibration not run: " + calibration_skipped->reason + "\n  " +
            calibration_skipped->action + "\n";
  }
  if (reconstruction) text += reconstruction->BriefReport();
  return text;
}

Result<CaptureAndProcessSummary> CaptureAndProcess(const CaptureAndProcessOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(CaptureOptions capture, MakeCaptureOptions(options));
  std::unique_ptr<TagDetectionSink> sink;
  if (options.calibrate) {
    HR_ASSIGN_OR_RETURN(sink, MakeDetectionSink(capture, options.threads));
  }
  FrameSinks sinks;
  sinks.Add(sink.get());
  sinks.Add(options.sink);
  if (!sinks.empty()) capture.sink = &sinks;
  capture.control = options.control;
  CaptureAndProcessSummary summary;
  HR_ASSIGN_OR_RETURN(summary.capture, RunCapture(capture));
  if (options.on_captured) options.on_captured(summary.capture);
  if (!sink || summary.capture.status != "complete") return summary;
  // The calibration's files honour storage.min_free_mb as the capture's did:
  // without room, the complete capture is kept as it is and the calibration
  // is reported as skipped.
  const Status room =
      CheckRoomForCalibration(capture.out_dir, *CaptureStorageFor(capture, options.rig));
  if (room.code() == StatusCode::kIoError) {
    const std::string action =
        "The capture is complete; free space on its disk, then run "
        "`hairrig calibrate " +
        summary.capture.dir + "` (or this command again with --resume)";
    summary.calibration_skipped = SkippedCalibration{room.ToString(), action};
    return summary;
  }
  HR_RETURN_IF_ERROR(room);
  HR_ASSIGN_OR_RETURN(
      summary.calibration,
      CalibrateAfterCapture(capture.out_dir, options.intrinsics_files, options.threads, *sink));
  if (options.reconstruct &&
      summary.calibration->calibration.verdict.level != CalibrationVerdict::Level::kFailed) {
    ReconstructCaptureOptions reconstruct;
    reconstruct.dir = capture.out_dir;
    reconstruct.points.threads = options.threads;
    reconstruct.strands.threads = options.threads;
    HR_ASSIGN_OR_RETURN(summary.reconstruction, ReconstructCapture(reconstruct));
  }
  return summary;
}

}  // namespace hairrig
