// `hairrig capture` as one library call: a capture (rig/capture.h), and with
// `calibrate` its calibration (tags detected as the frames land, the capture
// calibrated once it completes, rig/calibrate_capture.h), and with
// `reconstruct` its reconstruction (rig/reconstruct_capture.h) when the
// calibration has not failed.
#pragma once

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "rig/calibrate_capture.h"
#include "rig/capture.h"
#include "rig/reconstruct_capture.h"

namespace hairrig {

struct CaptureAndProcessOptions {
  // The rig config; empty: the simulated rig (DefaultRigConfigPath). Ignored
  // with resume (the capture's own rig.yaml snapshot is used; a warning is logged).
  std::string config_path;
  // The capture folder: must not exist unless resume. With a subject: the
  // folder of captures (created), the capture going to <out_dir>/<subject's
  // folder name> (rig/safe_names.h SubjectFolderName).
  std::string out_dir;
  std::string subject;  // the subject or wig name; recorded in the journal and manifest
  // With a subject: the capture's folder name under out_dir instead of the
  // subject's (checked as SubjectFolderName checks a subject).
  std::string folder_name;
  bool resume = false;       // continue an interrupted capture
  bool calibrate = false;    // detect the box's tags as frames land, calibrate a complete capture
  bool reconstruct = false;  // needs calibrate
  std::vector<std::string>
      intrinsics_files;  // needs calibrate: intrinsics held (CalibrateFolderOptions::prior_files)
  int threads = 2;       // tag detection as frames land, calibration and reconstruction
  std::function<void(const CaptureProgress&)>
      on_progress;  // optional, called from the sequencer thread
  std::function<void(const CaptureSummary&)>
      on_captured;            // optional, once the capture ends, before calibrating
  FrameSink* sink = nullptr;  // optional: told of each stored frame, beside the tag detection
  std::shared_ptr<CaptureControl> control;  // optional: stop or e-stop the capture
  Rig* rig = nullptr;  // optional: a rig already built (CaptureOptions::rig); config_path unused

  // InvalidArgument naming the option: no out_dir, intrinsics_files or
  // reconstruct without calibrate, threads below 1.
  Status Check() const;
};

// The calibration of a capture calibrated as it was shot, with the delays
// from the last frame stored (s, steady clock).
struct CalibrationAfterCapture {
  CalibratedFolder calibration;
  int frames_detected_during_capture = 0;
  double detection_backlog_s = 0;  // until the last frame's tags were detected
  double capture_closed_s = 0;     // until the capture was closed (contact sheet, ground truth)
  double calibration_after_last_frame_s = 0;  // until calibration.json and the exports were written
  double delay_after_last_frame_s = 0;        // until the report was written
};

// A calibration asked for (`calibrate`) and not run although the capture
// completed: its disk has no room for the calibration's files.
struct SkippedCalibration {
  std::string reason;  // the free-space check's IoError, naming the folder and storage.min_free_mb
  std::string action;  // what to do: free space, then `hairrig calibrate <capture>`
};

struct CaptureAndProcessSummary {
  CaptureSummary capture;
  std::optional<CalibrationAfterCapture> calibration;     // calibrate, and the capture complete
  std::optional<SkippedCalibration> calibration_skipped;  // calibrate, not run for lack of room
  std::optional<ReconstructCaptureSummary>
      reconstruction;  // reconstruct, and the calibration not failed

  // The capture's summary with "calibration" (the calibration's summary and
  // the delays) and "reconstruction" when they ran, "calibration_skipped"
  // ({"reason", "action"}) when the calibration was not run for lack of room.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors as RunCapture's (nothing captured), an unsafe subject name, a rig
// config without a usable calibration section (with calibrate), and the
// calibration's and reconstruction's errors; a capture that ends incomplete
// or stopped is a summary, not an error. So is a complete capture whose disk
// (rig/capture.h CaptureStorageFor) has no room for the calibration's files
// above its storage.min_free_mb (checked before calibrating, as before each
// frame): the calibration is not run, the capture keeps its status
// (`complete`, as manifest.json says) and `calibration_skipped` says why and
// what to run once there is room; the command line exits 3 for it.
Result<CaptureAndProcessSummary> CaptureAndProcess(const CaptureAndProcessOptions& options);

}  // namespace hairrig
