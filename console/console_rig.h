// The rig as the operator console drives it: one process owns the rig's
// devices (docs/design.md section 9). Between captures it keeps them open for the
// live view, the lights and the turntable; a capture, a resume and a replay run
// the same library calls as the command line (rig/capture_and_process.h,
// rig/replay_capture.h) on a worker thread, with this rig's devices, and report
// through the console's events. It holds no capture logic of its own.
//
// Every call is thread-safe (the HTTP server calls from its pool). Calls that
// use the devices return FailedPrecondition while a capture shoots (its
// calibration and reconstruction leave them to the console), and those that
// move or light the rig while the e-stop is active; EStop works at any time.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

#include "console/capture_archive.h"
#include "console/event_hub.h"
#include "console/live_view.h"
#include "core/status.h"
#include "rig/capture_plan.h"

namespace hairrig {

struct Rig;
class CaptureControl;
class ConsoleFrameSink;

struct ConsoleRigOptions {
  std::string config_path;   // the rig config; empty: the simulated rig (DefaultRigConfigPath)
  std::string captures_dir;  // where captures are written and listed (created)
  LiveViewOptions live;
  int threads = 2;               // tag detection, calibration and reconstruction after a capture
  int thumbnail_width_px = 240;  // 16..4096

  // InvalidArgument naming the field: no captures_dir, live.* (LiveViewOptions::Check),
  // threads below 1, thumbnail_width_px outside [16, 4096].
  Status Check() const;
};

class ConsoleRig {
 public:
  ConsoleRig(ConsoleRigOptions options, EventHub& events);
  ~ConsoleRig();
  ConsoleRig(const ConsoleRig&) = delete;
  ConsoleRig& operator=(const ConsoleRig&) = delete;

  // Loads the config (errors name file, line and field), builds the rig, reads
  // the plan, opens every device (one that fails is reported by Devices(), not
  // here) and starts the live view.
  Status Start();
  // A running capture is stopped as by StopCapture and waited for (it stays
  // resumable), then the devices are closed.
  void Shutdown();

  // {"version", "rig", "estop", "busy", "capture", "turntable", "lights"}
  // (docs/console-api.md); "control" is the server's.
  nlohmann::json State();
  // {"devices": [...]}: name, kind, backend, serial, model, state, health (a
  // health check each while idle; "in use by the capture" while one runs).
  nlohmann::json Devices();
  Result<nlohmann::json> Reconnect(const std::string& device_name);
  nlohmann::json Cameras();
  Result<nlohmann::json> SetCameraExposure(const std::string& camera_name,
                                           std::optional<double> exposure_s,
                                           std::optional<double> gain_db);
  Result<nlohmann::json> SetLights(const std::map<std::string, bool>& on);
  Result<nlohmann::json> Jog(double degrees);
  Result<nlohmann::json> Home();
  // {"views", "stops", "cameras", "exposure_s", "gain_db", "expected_s"}.
  nlohmann::json Plan() const;

  // Starts a capture on the worker thread; returns its id (the subject's
  // folder name and the UTC start time). FailedPrecondition while busy or in
  // e-stop, InvalidArgument for a subject that cannot name a folder.
  Result<std::string> StartCapture(const std::string& subject, bool calibrate, bool reconstruct);
  // Resumes capture `id` (NotFound, InvalidArgument as the archive's).
  Result<std::string> ResumeCapture(const std::string& id, bool calibrate, bool reconstruct);
  // Replays capture `id` into "<id>-replay" (rig/replay_capture.h).
  Result<std::string> ReplayCapture(const std::string& id);
  // Ends the running capture after its current stop (resumable).
  Status StopCapture(const std::string& who);
  // Stops the turntable at once and switches the lights off, ends a running
  // capture (resumable), and refuses motion until ReleaseEStop.
  nlohmann::json EStop(const std::string& who);
  Status ReleaseEStop();

  std::optional<LivePreview> Preview(const std::string& camera_name) const;
  bool HasCamera(const std::string& camera_name) const;
  const CaptureArchive& archive() const { return archive_; }
  // The thumbnail of a view stored by this process's captures, if still held.
  std::optional<std::vector<uint8_t>> CachedThumbnail(const std::string& id, int view) const;

 private:
  friend class ConsoleFrameSink;
  enum class Busy { kIdle, kCapturing, kProcessing, kReplaying };
  static const char* BusyName(Busy busy);

  // FailedPrecondition naming `what` while a capture uses the devices, or
  // when `moves` (motion or light) and the e-stop is active.
  Status CheckDevicesFree(const char* what, bool moves) const;
  void ReturnDevicesToConsole();
  nlohmann::json NewCaptureStatus(const std::string& id, const std::string& subject, int views_done,
                                  int views_total, const std::string& step) const;
  // Makes the rig busy with a capture whose status is `status`; FailedPrecondition
  // starting with `what` while busy or in e-stop.
  Status ClaimForCapture(const std::string& what, nlohmann::json status);
  void PublishState();
  void RunOnWorker(std::function<void()> job);
  void StartLiveView();
  void StopLiveView();
  void WatchSafetyInputs();
  void RunCaptureJob(const std::string& id, const std::string& subject, bool resume, bool calibrate,
                     bool reconstruct);
  void OnProgress(const std::string& id, const struct CaptureProgress& progress);
  void OnViewStored(const std::string& id, int view, const std::string& camera,
                    const cv::Mat& image);
  void LightsOffAndStop();

  const ConsoleRigOptions options_;
  EventHub& events_;
  CaptureArchive archive_;
  LiveView live_;
  std::unique_ptr<Rig> rig_;
  CapturePlan plan_;
  double plan_lower_bound_s_ = 0;

  std::mutex rig_mutex_;            // serialises calls that use the devices between captures
  mutable std::mutex state_mutex_;  // guards the fields below
  Busy busy_ = Busy::kIdle;
  bool estop_active_ = false;
  std::string estop_reason_;
  nlohmann::json capture_;  // the current or last capture's status; null before the first
  std::map<std::string, bool> lights_on_;
  std::shared_ptr<CaptureControl> control_;  // the running capture's
  std::map<std::pair<std::string, int>, std::vector<uint8_t>> thumbnails_;
  int64_t last_progress_ns_ = 0;
  int last_progress_views_ = -1;
  int last_faults_ = 0;

  std::thread worker_;
};

}  // namespace hairrig
