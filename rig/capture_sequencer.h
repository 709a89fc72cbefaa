// Internal to rig/capture.cpp's RunCapture (rig/capture.h): the sequencer
// that shoots one session of a capture plan into its capture dataset. Only
// rig/capture.cpp and the sequencer's own sources include this header.
//
// Per stop of a sweep it moves the turntable (degrees, the plan's angles) and
// waits for its in-position flag and settle time, sets the LED panels,
// triggers the stop's cameras (one pulse per trigger line, else a software
// trigger each) and queues a shot for each camera's collector thread, which
// waits for the frame and stores it in the dataset while the turntable moves
// on. Waits are wall seconds: device seconds times each device's time_scale.
// The views still without a verified frame are shot again in re-shoot passes,
// up to the camera policy's attempts; a camera that dropped off is reopened
// with back-off first.
//
// Faults do not make it fail: each is journalled and counted, and the summary
// says how the session ended ("complete", "incomplete" or "stopped"). A safety
// input going active or unreadable, or a software e-stop, stops motion and
// turns the lights off at once, then ends the run; an operator's stop, a setup
// failure, a turntable or light fault its retries do not clear and the first
// storage failure end it before another stop is shot.
//
// Threads: RunCapture's thread calls the public methods; each camera's
// collector, the safety inputs' callbacks and the capture observers' writes
// run on their own threads.
//
// Sources: capture_sequencer.cpp (setup, safety stops and the sweep),
// capture_collection.cpp (the collectors) and capture_bookkeeping.cpp
// (faults, progress and ETA, the summary and the session's end).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/capture_storage.h"
#include "core/status.h"
#include "rig/capture.h"
#include "rig/capture_control.h"
#include "rig/capture_dataset.h"
#include "rig/capture_plan.h"
#include "rig/rig_config.h"

namespace hairrig {
namespace detail {

// `seconds` as a device timeout: whole milliseconds, rounded up, at least 1.
std::chrono::milliseconds Ms(double seconds);

}  // namespace detail

// One camera's shot of one view, waiting for its frame.
struct Shot {
  int view = 0;
  int stop = 0;
  int64_t trigger_ns = 0;
  std::chrono::steady_clock::time_point deadline;
  double angle_commanded_deg = 0;
  double angle_measured_deg = 0;
};

// A camera of the rig, its queue of shots and its collector thread.
struct CameraSlot {
  Camera* camera = nullptr;
  std::deque<Shot> queue;
  bool busy = false;  // the collector is working on a shot
  bool needs_reopen =
      false;  // dropped off the bus, or its frames can no longer be paired with triggers
  int gave_up_in_pass = 0;  // reopening failed every attempt in this pass: skip it until the next
  std::thread collector;
};

// Runs one capture session as the file comment says.
class Sequencer {
 public:
  Sequencer(Rig& rig, const CapturePlan& plan, const CapturePolicies& policies,
            CaptureDataset& dataset, const CaptureOptions& options)
      : rig_(rig), plan_(plan), policies_(policies), dataset_(dataset), options_(options) {}

  ~Sequencer() { StopCollectors(); }

  // Shoots the views still missing, unless the session already stopped;
  // tells the frame sink the capture finished.
  void Run();
  // The session so far (status from how it ended, or would end now).
  CaptureSummary Summary();
  // Journals session_end and writes the manifest with `summary`'s status; a
  // storage failure of either stops the session (`summary` says so; --resume
  // writes both again).
  void EndSession(CaptureSummary* summary);
  // Stops the run for a storage failure (a write's IoError, a file refused by
  // storage.min_free_mb): journals it, and the summary says to free space,
  // then --resume. The first such failure only.
  void StopForStorage(const Status& status, const Device* device = nullptr, int view = -1);
  bool Stopping() const { return stop_run_.load() || estop_.load(); }
  // A storage failure stopped the session: nothing more is written.
  bool StorageFailed() const { return storage_failed_.load(); }
  // CaptureFolder::write for the capture observers: the dataset's WriteFile.
  // Its first storage failure stops the run at the next stop (from the
  // sequencer's thread: the writer runs on the simulated cameras' threads).
  FileWriter ObserverWriter();

 private:
  // --- setup and teardown (capture_sequencer.cpp) ---
  Status Setup();
  void StopCollectors();
  void OnSafetyInput(const InputLine& line, bool active);
  void OnControl(CaptureControl::Kind kind, const std::string& reason);
  void SafetyStop(const std::string& what, const std::string& input_name, const Device* device,
                  const Status& fault);

  // --- the sweep (capture_sequencer.cpp) ---
  void RunPass(const std::vector<int>& views, int pass);
  bool ShootStop(const PlannedStop& stop, const std::vector<int>& views);
  Status Move(double angle_deg, double* measured_deg);
  Status SetLights(const std::map<std::string, double>& levels);
  void PulseTriggerLine(const std::string& line_name, int64_t sent_ns);
  void AllLightsOff();
  Status EnsureCameraReady(CameraSlot& slot);
  Status PrepareCamera(Camera& camera);
  void WaitCollectorsIdle();

  // --- collection (capture_collection.cpp) ---
  void CollectorLoop(CameraSlot& slot);
  bool Collect(CameraSlot& slot, const Shot& shot);

  // --- bookkeeping (capture_bookkeeping.cpp) ---
  void RecordFault(const Device* device, const Status& status, const std::string& action,
                   int view = -1);
  void StopRun(const std::string& why);
  Status ObserverFailure();
  std::vector<int> MissingViews() const;
  void Progress(const std::string& step, int stop);
  void PlanEta(const std::map<int, std::vector<int>>& views_by_stop);
  void CountStopDone(int stop);
  double EtaLocked(int views_left) const;
  double PlannedBoundLeftLocked() const;
  double ExpectedFrameWallS(const Camera& camera) const;

  Rig& rig_;
  const CapturePlan& plan_;
  const CapturePolicies& policies_;
  CaptureDataset& dataset_;
  const CaptureOptions& options_;

  std::map<std::string, CameraSlot> slots_;  // by serial
  std::mutex mutex_;
  std::condition_variable cv_;
  bool shutdown_ = false;

  std::atomic<bool> stop_run_{false};
  std::atomic<bool> estop_{false};
  std::atomic<bool> storage_failed_{false};  // nothing more is written
  std::string stop_reason_;                  // guarded by mutex_
  std::mutex observer_mutex_;
  Status observer_failure_;  // guarded by observer_mutex_: the observers' first storage failure
  int views_kept_ = 0;       // verified before this session
  double setup_s_ = 0;
  std::atomic<int> faults_{0};
  std::atomic<int> frames_{0};
  std::atomic<uint64_t> bytes_{0};
  std::chrono::steady_clock::time_point sweep_start_{}, last_frame_{};
  double lower_bound_s_ = 0;
  double last_download_s_ = 0;
  std::atomic<int> stops_done_{0}, stops_total_{0};
  std::atomic<int> sweep_stop_{0};  // the stop the turntable is at or moving to
  int pass_ = 0;
  std::mutex progress_mutex_;
  // The ETA, guarded by progress_mutex_: the lower bound of each stop this
  // pass has still to shoot, and of the stops done since the sweep began.
  std::map<int, double> bound_left_s_;
  std::string last_fault_;  // guarded by progress_mutex_
  double bound_done_s_ = 0;
};

}  // namespace hairrig
