// The `replay` device backend: a recorded capture folder plays the part of
// the rig that recorded it, so the sequencer and every later stage run on it
// with no hardware (docs/design.md sections 2 and 4).
//
// The turntable reports the recorded measured angle of the stop whose
// commanded angle it is sent to; each camera, when triggered, serves the
// recorded file of its serial at that stop, byte for byte (as an encoded
// frame), so a capture made from a replay has the same checksums. Lights,
// trigger lines and input lines behave like idle hardware. With speed > 0 the
// recorded timing is reproduced (moves take the recorded time between stops,
// frames arrive after their recorded download time), divided by `speed`;
// with speed 0 everything happens at once.
#pragma once

#include <memory>
#include <string>

#include "drivers/registry.h"

namespace hairrig {

class ReplaySource;

struct ReplayOptions {
  double speed = 0;  // 0: as fast as possible; 1: recorded timing; 2: twice as fast

  // InvalidArgument naming speed unless it is 0 or a finite positive factor.
  Status Check() const;
};

// Reads the capture's journal and serves its verified frames only
// (rig/capture_dataset.h VerifiedFrames: inside the folder, size and SHA-256
// as recorded; checked again when a frame is served). NotFound / CorruptData
// name the folder, file, journal line and field; InvalidArgument for bad options
// (ReplayOptions::Check).
Result<std::shared_ptr<ReplaySource>> OpenReplaySource(const std::string& capture_dir,
                                                       const ReplayOptions& options);
int ReplayFrameCount(const ReplaySource& source);

// InvalidArgument when `out_dir` (symlinks resolved) is the recording or lies
// inside it: replay never writes into what it replays.
Status CheckReplayOutDir(const std::string& recorded_dir, const std::string& out_dir);

// Registers the `replay` backend of every device kind, serving `source`.
void RegisterReplayBackends(DeviceRegistry* registry, std::shared_ptr<ReplaySource> source);

}  // namespace hairrig
