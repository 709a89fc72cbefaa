// Internal to the `sim` backend (sim_hw/sim_devices.h): the simulated world
// its devices share, behind the World* functions of sim_devices.h. Included
// by sim_devices.cpp (the devices), sim_world_model.cpp (the world's
// functions) and sim_turntable_controller.cpp (the controller that moves its
// platform); no other file sees the class.
//
// The world holds the turntable platform's motion (trapezoidal moves,
// degrees), the safety inputs and their callbacks, the scene lights' levels
// (0..1), the trigger bus, the ground-truth recorder, each scene camera's last
// radiance, and the per-device event counts that decide which configured
// faults (sim_hw/sim_faults.h) hit. Times are device seconds; time_scale maps
// them to wall time (steady clock). One mutex guards the state; the input
// callbacks run outside it.
//
// Failures: SetLightLevel returns NotFound for a light the scene lacks; a move
// jammed by a turntable_timeout fault never reaches position
// (SecondsToInPosition is +infinity).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/status.h"
#include "drivers/trigger_bus.h"
#include "drivers/turntable.h"
#include "sim_hw/renderer.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_faults.h"
#include "sim_hw/sim_turntable_controller.h"

namespace hairrig {
namespace detail {

// Trapezoidal (or triangular) move: position (deg, signed as `distance`)
// after `t` seconds of a move of `distance` deg at the given speed and
// acceleration; `distance` once MoveDurationS has passed.
double TrapezoidPosition(double distance, const MotionProfile& p, double t);

}  // namespace detail

// The simulated world of the file comment, shared by the `sim` devices.
class SimWorld {
 public:
  using Clock = std::chrono::steady_clock;

  SimWorld(std::unique_ptr<Renderer> renderer, SimWorldOptions options)
      : renderer_(std::move(renderer)),
        options_(std::move(options)),
        turntable_controller_(std::make_unique<SimTurntableController>(*this)) {
    for (const SceneLight& l : renderer_->scene().lights) light_levels_[l.name] = 0.0;
  }
  ~SimWorld() {
    if (estop_timer_.joinable()) estop_timer_.join();
  }

  // --- fault injection --------------------------------------------------
  // Counts one more event of `device` ("" for the turntable) and returns the
  // first configured fault of `kind` that hits it, or nullptr.
  const SimFault* NextEventFault(const std::string& device,
                                 std::initializer_list<SimFaultKind> kinds) {
    std::lock_guard<std::mutex> lock(mutex_);
    const int event = ++event_counts_[device];
    for (const SimFault& f : options_.faults) {
      for (SimFaultKind k : kinds) {
        if (f.kind == k && f.device == device && f.Hits(event)) return &f;
      }
    }
    return nullptr;
  }
  const SimFault* FindFault(SimFaultKind kind) const {
    for (const SimFault& f : options_.faults) {
      if (f.kind == kind) return &f;
    }
    return nullptr;
  }
  const Renderer& renderer() const { return *renderer_; }
  const Scene& scene() const { return renderer_->scene(); }
  double time_scale() const { return options_.time_scale; }
  bool noise() const { return options_.noise; }

  // Sleeps `sim_seconds` of simulated time.
  void SleepSim(double sim_seconds) const {
    if (sim_seconds > 0)
      std::this_thread::sleep_for(std::chrono::duration<double>(sim_seconds * options_.time_scale));
  }
  double SimSecondsSince(Clock::time_point t0) const {
    return std::chrono::duration<double>(Clock::now() - t0).count() / options_.time_scale;
  }

  // --- turntable motion -------------------------------------------------
  void StartMove(double target_deg, const MotionProfile& p) {
    std::lock_guard<std::mutex> lock(mutex_);
    move_start_deg_ = AngleLocked();
    move_target_deg_ = target_deg;
    move_profile_ = p;
    move_start_ = Clock::now();
    stuck_ = false;
  }
  // Simulated seconds until the platform stops moving (settle excluded).
  double MotionSecondsLeft() const {
    std::lock_guard<std::mutex> lock(mutex_);
    const double duration = MoveDurationS(move_target_deg_ - move_start_deg_, move_profile_);
    return std::max(0.0, duration - SimSecondsSince(move_start_));
  }
  // The current move never sets the in-position flag (the controller hunts
  // around the target: a following-error loop that never settles).
  void JamMove() {
    std::lock_guard<std::mutex> lock(mutex_);
    stuck_ = true;
  }
  double AngleDeg() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return AngleLocked();
  }
  // Simulated seconds until in position (move plus settle); 0 when there.
  double SecondsToInPosition() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stuck_) return std::numeric_limits<double>::infinity();
    const double duration = MoveDurationS(move_target_deg_ - move_start_deg_, move_profile_);
    return std::max(0.0, duration + scene().turntable_settle_s - SimSecondsSince(move_start_));
  }
  void StopMotion() {
    std::lock_guard<std::mutex> lock(mutex_);
    move_start_deg_ = move_target_deg_ = AngleLocked();
    move_start_ = Clock::now();
    stuck_ = false;
  }

  // --- safety inputs ----------------------------------------------------
  using InputFn = std::function<void(bool)>;
  void SetInputCallback(const std::string& line, InputFn fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (fn)
      input_callbacks_[line] = std::move(fn);
    else
      input_callbacks_.erase(line);
  }
  bool InputActive() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return input_active_;
  }
  void SetInputActive(bool active) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (input_active_ == active) return;
      input_active_ = active;
    }
    NotifyInputs(active);
  }
  // The safety inputs' wiring is broken (an input_lost fault): they cannot be
  // read from then on.
  bool InputsLost() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return inputs_lost_;
  }
  // `after_s` device seconds from now, from another thread: presses the e-stop
  // (kEstop) or breaks the inputs' wiring (kInputLost), telling the lines'
  // callbacks `true` either way. Until the callbacks have been told,
  // SafetyEventPending() is true: the turntable's move it belongs to does not
  // end before it (on a loaded machine the thread may wake well after
  // `after_s`, while the rig would otherwise go on to the next stop's views).
  void ScheduleSafetyEvent(SimFaultKind kind, double after_s) {
    if (estop_timer_.joinable()) estop_timer_.join();
    safety_event_pending_ = true;
    estop_timer_ = std::thread([this, kind, after_s] {
      SleepSim(after_s);
      if (kind == SimFaultKind::kInputLost) {
        std::lock_guard<std::mutex> lock(mutex_);
        inputs_lost_ = true;
      }
      NotifyInputs(true);
      safety_event_pending_ = false;
    });
  }
  bool SafetyEventPending() const { return safety_event_pending_; }

  // --- lights -----------------------------------------------------------
  Status SetLightLevel(const std::string& name, double level) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = light_levels_.find(name);
    if (it == light_levels_.end()) return NotFound("the scene has no light '" + name + "'");
    it->second = level;
    return Status::Ok();
  }
  double LightLevel(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = light_levels_.find(name);
    return it == light_levels_.end() ? 0.0 : it->second;
  }
  std::vector<double> LightLevels() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<double> levels;
    for (const SceneLight& l : scene().lights) levels.push_back(light_levels_.at(l.name));
    return levels;
  }

  // --- trigger lines ----------------------------------------------------
  TriggerBus& triggers() { return triggers_; }

  SimTurntableController& turntable_controller() { return *turntable_controller_; }

  void SetTruthRecorder(WorldTruthRecorder recorder) {
    std::lock_guard<std::mutex> lock(mutex_);
    truth_recorder_ =
        recorder ? std::make_shared<const WorldTruthRecorder>(std::move(recorder)) : nullptr;
  }
  std::shared_ptr<const WorldTruthRecorder> truth_recorder() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return truth_recorder_;
  }

  // --- the last radiance each scene camera rendered -----------------------
  // A frame of an unchanged world (same turntable angle and light levels) is
  // exposed again from it, with its own noise, instead of rendered again.
  struct CachedRadiance {
    WorldExposure world;
    cv::Mat3f radiance;
  };
  std::shared_ptr<const CachedRadiance> CachedRadianceFor(int scene_camera,
                                                          const WorldExposure& exposure) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = radiance_cache_.find(scene_camera);
    if (it == radiance_cache_.end() || !SameWorld(it->second->world, exposure)) return nullptr;
    return it->second;
  }
  void CacheRadiance(int scene_camera, const WorldExposure& exposure, cv::Mat3f radiance) const {
    auto entry =
        std::make_shared<const CachedRadiance>(CachedRadiance{exposure, std::move(radiance)});
    std::lock_guard<std::mutex> lock(mutex_);
    radiance_cache_[scene_camera] = std::move(entry);
  }

 private:
  static bool SameWorld(const WorldExposure& a, const WorldExposure& b) {
    return std::abs(a.angle_deg - b.angle_deg) < 1e-9 && a.light_levels == b.light_levels;
  }
  void NotifyInputs(bool active) {
    std::vector<InputFn> fns;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto& [name, fn] : input_callbacks_) fns.push_back(fn);
    }
    for (auto& fn : fns) fn(active);
  }
  double AngleLocked() const {
    return move_start_deg_ + detail::TrapezoidPosition(move_target_deg_ - move_start_deg_,
                                                       move_profile_, SimSecondsSince(move_start_));
  }

  std::unique_ptr<Renderer> renderer_;
  SimWorldOptions options_;
  mutable std::mutex mutex_;
  double move_start_deg_ = 0, move_target_deg_ = 0;
  MotionProfile move_profile_;
  Clock::time_point move_start_ = Clock::now();
  std::map<std::string, double> light_levels_;
  TriggerBus triggers_;
  bool stuck_ = false;
  std::map<std::string, int> event_counts_;
  std::map<std::string, InputFn> input_callbacks_;
  bool inputs_lost_ = false;
  bool input_active_ = false;
  std::thread estop_timer_;
  std::atomic<bool> safety_event_pending_{false};
  std::unique_ptr<SimTurntableController> turntable_controller_;
  std::shared_ptr<const WorldTruthRecorder> truth_recorder_;
  mutable std::map<int, std::shared_ptr<const CachedRadiance>> radiance_cache_;
};

}  // namespace hairrig
