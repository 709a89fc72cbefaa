#include "rig/replay_capture.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/string_format.h"
#include "rig/capture_calibration_input.h"
#include "rig/replay.h"

namespace hairrig {

namespace fs = std::filesystem;

Status ReplayCaptureOptions::Check() const {
  if (recorded_dir.empty())
    return InvalidArgument("replay: the recorded capture folder is required");
  if (!std::isfinite(speed) || speed < 0)
    return InvalidArgument("replay: --speed must be 0 or a positive number");
  return Status::Ok();
}

nlohmann::json ReplayCaptureSummary::ToJson() const {
  nlohmann::json out = capture.ToJson();
  out["replayed_from"] = replayed_from;
  out["recorded_frames"] = recorded_frames;
  return out;
}

std::string ReplayCaptureSummary::BriefReport() const {
  std::string text =
      StringPrintf("replayed %s (%d recorded frames) into %s: %s\n", replayed_from.c_str(),
                   recorded_frames, capture.dir.c_str(), capture.status.c_str());
  text += StringPrintf("  views %d of %d, %d frames, %.2f s\n", capture.views_completed,
                       capture.views_planned, capture.frames, capture.wall_s);
  if (!capture.message.empty()) text += "  " + capture.message + "\n";
  return text;
}

Result<ReplayCaptureSummary> ReplayCapture(const ReplayCaptureOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string out_dir =
      options.out_dir.empty() ? options.recorded_dir + "-replay" : options.out_dir;
  HR_RETURN_IF_ERROR(CheckReplayOutDir(options.recorded_dir, out_dir));
  HR_ASSIGN_OR_RETURN(std::shared_ptr<ReplaySource> source,
                      OpenReplaySource(options.recorded_dir, {.speed = options.speed}));
  HR_ASSIGN_OR_RETURN(RigConfig config, LoadCaptureRigConfig(options.recorded_dir));
  CaptureOptions capture;
  capture.config_path = config.path;
  capture.config_relative_to = config.relative_to;
  capture.out_dir = out_dir;
  capture.rig_build.register_backends = [source](DeviceRegistry* registry) {
    RegisterReplayBackends(registry, source);
  };
  capture.rig_build.backend_override = "replay";
  capture.rig_build.attach_extensions = false;
  ReplayCaptureSummary summary;
  HR_ASSIGN_OR_RETURN(summary.capture, RunCapture(capture));
  summary.replayed_from = options.recorded_dir;
  summary.recorded_frames = ReplayFrameCount(*source);
  return summary;
}

}  // namespace hairrig
