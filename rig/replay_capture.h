// A recorded capture run again through the sequencer, its devices served by
// the `replay` backend (rig/replay.h): what `hairrig replay` does.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/status.h"
#include "rig/capture.h"

namespace hairrig {

struct ReplayCaptureOptions {
  std::string recorded_dir;  // a capture folder made by `hairrig capture`
  std::string
      out_dir;       // the new capture folder; must not exist (default: recorded_dir + "-replay")
  double speed = 0;  // 0: as fast as possible; 1: recorded timing; 2: twice as fast

  Status Check() const;
};

struct ReplayCaptureSummary {
  CaptureSummary capture;
  std::string replayed_from;
  int recorded_frames = 0;
  nlohmann::json ToJson() const;  // the capture's summary plus replayed_from and recorded_frames
  std::string BriefReport() const;
};

// Runs the recording's own config snapshot (rig.yaml, its relative paths
// resolved where the original config's were) with every device replaced by
// the recording. Errors: the recording cannot be read or verified, the config
// snapshot does not load, out_dir exists.
Result<ReplayCaptureSummary> ReplayCapture(const ReplayCaptureOptions& options);

}  // namespace hairrig
