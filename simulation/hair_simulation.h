// A hairstyle in motion: every guide of a fitted model (simulation/helix_model.h)
// as a super-helix (simulation/super_helix_dynamics.h), started from inverse
// statics, driven by a scenario (gravity alone, a head shake, wind), stepped
// in parallel over guides. Input and output strands are in millimetres in the
// model's world frame; the dynamics run in SI units in the head's frame.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "simulation/helix_model.h"
#include "simulation/super_helix_dynamics.h"

namespace hairrig {

enum class Scenario { kGravity, kHeadShake, kWind };
// "gravity", "head-shake", "wind"; InvalidArgument lists the choices.
Result<Scenario> ParseScenario(const std::string& name);
const char* ScenarioName(Scenario scenario);

struct HairSimulationOptions {
  HairMaterial material;
  DynamicsOptions dynamics;
  Scenario scenario = Scenario::kGravity;
  Eigen::Vector3d up{0, 0, 1};  // world up (unit); gravity is 9.81 m/s^2 against it
  // The head (world frame, mm): contact, and the pivot of the head shake.
  bool has_head = false;
  Eigen::Vector3d head_center_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d head_radii_mm = Eigen::Vector3d::Ones();
  // With has_head: contact with this head's surface (world frame, mm; e.g. the
  // mesh strands were reconstructed on) instead of the ellipsoid above, which
  // stays the shake's pivot (its centre).
  std::shared_ptr<const HeadModel> head_surface;
  double shake_amplitude_deg = 30;  // head-shake: a turn about `up` through the head centre
  double shake_frequency_hz = 1.5;
  Eigen::Vector3d wind_m_s{2.0, 0, 0};  // wind: mean air velocity, gusting +-40 % at 0.7 Hz
  bool inverse_statics = true;          // Sec. VI: the fitted shape is the rest state
  // Contact holds each point of a guide no nearer the head than it rests
  // (SuperHelixDynamics::HoldContactAtRest), so a guide fitted onto or into
  // the head starts without contact forces; false: the margin everywhere.
  bool contact_from_rest = true;
  int threads = 0;  // 0: one per core

  // InvalidArgument naming the field (material.* and dynamics.* for the
  // nested ones) for a value out of range or not finite.
  Status Check() const;
};

struct HairSimulationStats {
  long long steps = 0;
  long long contact_samples = 0;  // summed over guides and steps
  double mean_solver_iterations = 0;
  double max_inverse_statics_change = 0;  // rad/m
};

class HairSimulation {
 public:
  // InvalidArgument for a model with no guide, bad options (named), or a guide
  // that cannot become a super-helix (named by index).
  static Result<std::unique_ptr<HairSimulation>> Create(const HelixModel& model,
                                                        const HairSimulationOptions& options);
  ~HairSimulation();

  // Steps until `seconds` more of simulated time have passed. A failing guide
  // is named; the others keep their state.
  Status Advance(double seconds);
  double time_s() const;

  // The world from the head frame now (rotation, then translation in mm).
  Eigen::Matrix3d head_rotation() const;
  Eigen::Vector3d head_translation_mm() const;

  // Each guide's centreline now, `per_element` points per element plus the
  // root, world frame, mm.
  std::vector<std::vector<Eigen::Vector3d>> GuideCurves(int per_element) const;
  int num_guides() const;
  const HairSimulationStats& stats() const;

  // The environment (simulation frame) at time t: for tests and benches.
  Environment EnvironmentAt(double t) const;

 private:
  struct Impl;
  explicit HairSimulation(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
