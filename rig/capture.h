// The capture sequencer: runs a rig's plan (rig/capture_plan.h) into a capture
// dataset (rig/capture_dataset.h).
//
// Per stop: move the turntable and wait for its in-position flag and settle
// time, set the LED panels, trigger every camera of the stop together (one
// pulse per shared trigger line, else a software trigger each), and move on as
// soon as the exposure has ended. One collector thread per camera waits for
// its frames, checks, encodes, hashes and stores them while the turntable
// already moves to the next stop.
//
// Faults: a frame that does not arrive, arrives corrupt, or a camera that
// drops off the bus marks the view for a re-shoot pass after the first sweep
// (a camera is reopened with back-off first); a move that times out is
// re-commanded; a turntable fault, an e-stop or interlock stop the run at
// once. So does the first storage failure (a write's IoError, such as ENOSPC)
// and a frame that would leave less than storage.min_free_mb free: no stop is
// shot after it and frames still waiting to be stored are dropped. Every fault
// is journalled; the dataset stays consistent and `--resume` continues it.
//
// Every file of the session honours storage.min_free_mb and ends the session
// the same way on a storage failure: the session's journal records and the
// manifest (the check before each frame keeps room for them), the capture
// observers' files (the simulated rig's ground truth, written through
// CaptureFolder::write) and the contact sheet. A storage failure once the
// session has started, from journalling its start on (a frame, a journal
// record, the manifest, an observer's file, the contact sheet), gives the
// summary `stopped` (the command line's exit code 3), never an error; the
// contact sheet is then not written, and `--resume` writes what is missing.
//
// Storage failures before the session starts are RunCapture's IoError (the
// command line's exit code 1), with nothing shot; the same command runs again
// once there is room:
//  - creating a new capture folder (CaptureDataset::Create removes what it made);
//  - on a resume, repairing the folder (CaptureDataset::OpenForResume: cutting
//    a record left half-written, journalling journal_repaired, partial_removed
//    and file_quarantined) and journalling the views an interrupted start left
//    unplanned (CaptureDataset::JournalPlan);
//  - too little room for the views left to shoot (BytesNeededToFinish in
//    rig/capture_plan.h: all of them, or on a resume those without a verified
//    frame), checked before the session.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/capture_storage.h"
#include "core/frame_sink.h"
#include "core/status.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"

namespace hairrig {

class CaptureControl;  // rig/capture_control.h

struct CaptureProgress {
  int views_done = 0;  // verified views, earlier sessions included
  int views_total = 0;
  int stop = 0;  // the stop the turntable is at or moving to (0-based); frames of earlier
                 // stops may still be being stored
  int stops_total = 0;
  std::string step;  // "moving to 37.9 deg", "exposing", "re-shooting 2 views", ...
  double eta_s = 0;  // wall seconds left: the longer of the sweep's (the plan's lower bound of the
                     // stops left times its pace so far) and the storage's (views left times the
                     // wall time per view stored so far)
  int faults = 0;
  std::string last_fault;  // the newest fault and what was done about it; empty before the first
};

struct CaptureOptions {
  std::string config_path;  // rig config; ignored with resume (the snapshot is used)
  // The folder the config's relative paths (sim.scene, head, calibration.box)
  // resolve against; empty: the config's own folder.
  std::string config_relative_to;
  std::string out_dir;  // the capture folder: must not exist, unless resume
  std::string subject;  // recorded in the journal and manifest
  bool resume = false;
  FrameSink* sink = nullptr;  // optional
  std::function<void(const CaptureProgress&)>
      on_progress;            // optional, called from the sequencer thread
  RigBuildOptions rig_build;  // how devices are made (the replay command swaps in its backend)
  // Where the capture's files are written (core/capture_storage.h). Null: the
  // rig's own (Rig::capture_storage: the simulated rig's disk), else the file system.
  std::shared_ptr<CaptureStorage> storage;
  // Stop or e-stop the run from another thread (rig/capture_control.h); optional.
  std::shared_ptr<CaptureControl> control;
  // A rig already built from the config (the operator console's, its devices
  // closed): the capture opens, uses and closes its devices instead of
  // building its own. Null: RunCapture builds the rig (rig_build).
  Rig* rig = nullptr;

  // InvalidArgument naming the field: no out_dir (--out), bad rig_build.
  Status Check() const;
};

struct CaptureSummary {
  std::string dir;
  std::string status;   // "complete", "incomplete" (views missing after retries) or "stopped" (a
                        // fault ended the run)
  std::string message;  // what happened and what to do, for stopped/incomplete runs
  int views_planned = 0;
  int views_completed = 0;  // verified, earlier sessions included
  int views_kept = 0;       // verified frames kept from earlier sessions (resume)
  int frames = 0;           // frames stored in this session
  uint64_t bytes = 0;       // bytes stored in this session
  int faults = 0;           // faults in this session
  std::vector<int> missing_views;
  double setup_s = 0;  // opening devices, homing, arming
  double wall_s = 0;   // from the first stop's move to the last frame stored
  double lower_bound_s =
      0;                  // moves + settles + exposures of this session's stops + the last download
  double efficiency = 0;  // lower_bound_s / wall_s
  nlohmann::json ToJson() const;
};

// The capture folder as capture observers write to it.
struct CaptureFolder {
  std::string dir;  // absolute
  // Writes a file of the folder atomically through the capture's storage once
  // the free-space check the frames pass allows it (storage.min_free_mb):
  // IoError naming the file and the limit when it would leave less free, or
  // the write's IoError (ENOSPC). Callable from any thread until
  // OnCaptureEnd returns; a storage failure stops the run at its next stop.
  FileWriter write;
};

// Told when a capture begins and ends. The rig's extensions add theirs to the
// Rig they build (Rig::capture_observers): the simulated rig's writes the
// capture's ground truth. RunCapture calls them from its own thread.
// A storage failure (IoError, from `folder.write` or not) ends the session as
// a full disk does: the summary is `stopped`, resumable. Another error is
// RunCapture's, also when another observer's storage failed.
class CaptureObserver {
 public:
  virtual ~CaptureObserver() = default;
  // Once the capture folder holds the journalled `plan`, before anything
  // moves; on a resume too. Not called once the session has stopped (its
  // start could not be journalled, an earlier observer's storage failed);
  // OnCaptureEnd is called either way.
  virtual Status OnCaptureBegin(const CapturePlan& plan, const CaptureFolder& folder) = 0;
  // After the session's last frame, with the devices closed, whether the run
  // completed or not (each observer is told, whatever the others return).
  virtual Status OnCaptureEnd(const CaptureSummary& summary) = 0;
};

// Runs (or resumes) a capture. An error Status means nothing was captured
// (bad config, unusable folder, a storage failure before the session starts
// (above), devices that cannot be opened) or a capture observer failed other
// than by its storage (the first such error, whatever the others returned); a
// run that starts returns a summary, also when a fault (a storage failure
// included) stopped it.
Result<CaptureSummary> RunCapture(const CaptureOptions& options);

// Where a capture's files are written: options.storage, else the rig's own
// (Rig::capture_storage: the simulated rig's disk; `rig` may be null), else
// the file system (DefaultCaptureStorage). RunCapture writes there, and the
// stages run after it in the same command check their room there.
std::shared_ptr<CaptureStorage> CaptureStorageFor(const CaptureOptions& options, const Rig* rig);

}  // namespace hairrig
