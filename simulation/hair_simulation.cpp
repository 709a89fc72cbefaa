#include "simulation/hair_simulation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.h"
#include "core/transform.h"
#include "simulation/inverse_statics.h"
#include "simulation/super_helix.h"

namespace hairrig {

namespace {

constexpr double kGravity = 9.81;
constexpr double kRampS = 0.5;  // scenarios start smoothly over this time
constexpr double kGustHz = 0.7;
constexpr double kGustFraction = 0.4;

// 0 -> 1 over kRampS with zero slope at both ends.
double Ramp(double t) {
  const double x = std::clamp(t / kRampS, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

}  // namespace

Result<Scenario> ParseScenario(const std::string& name) {
  if (name == "gravity") return Scenario::kGravity;
  if (name == "head-shake") return Scenario::kHeadShake;
  if (name == "wind") return Scenario::kWind;
  return InvalidArgument("unknown scenario '" + name + "': choose gravity, head-shake or wind");
}

const char* ScenarioName(Scenario scenario) {
  switch (scenario) {
    case Scenario::kGravity:
      return "gravity";
    case Scenario::kHeadShake:
      return "head-shake";
    case Scenario::kWind:
      return "wind";
  }
  return "?";
}

struct HairSimulation::Impl {
  HairSimulationOptions options;
  std::vector<SuperHelixDynamics> dynamics;
  std::vector<StrandState> states;
  double time_s = 0;
  long long solver_iterations = 0;
  HairSimulationStats stats;

  // The head's turn about `up` (rad) at time t.
  double ShakeAngle(double t) const {
    if (options.scenario != Scenario::kHeadShake) return 0;
    return options.shake_amplitude_deg * kPi / 180 * Ramp(t) *
           std::sin(2 * kPi * options.shake_frequency_hz * t);
  }
  Eigen::Matrix3d HeadRotation(double t) const {
    return Eigen::AngleAxisd(ShakeAngle(t), options.up).toRotationMatrix();
  }
  Eigen::Vector3d PivotMm() const {
    return options.has_head ? options.head_center_mm : Eigen::Vector3d::Zero();
  }
};

Environment HairSimulation::EnvironmentAt(double t) const {
  const Impl& m = *impl_;
  Environment env;
  const Eigen::Matrix3d head_from_world = m.HeadRotation(t).transpose();
  env.gravity_m_s2 = head_from_world * (-kGravity * m.options.up);
  env.pivot_m = 1e-3 * m.PivotMm();
  if (m.options.scenario == Scenario::kHeadShake) {
    const double h = 1e-4;
    const double rate = (m.ShakeAngle(t + h) - m.ShakeAngle(t - h)) / (2 * h);
    const double acceleration =
        (m.ShakeAngle(t + h) - 2 * m.ShakeAngle(t) + m.ShakeAngle(t - h)) / (h * h);
    env.frame_angular_velocity =
        rate * m.options.up;  // `up` is the turn's axis: the same in both frames
    env.frame_angular_acceleration = acceleration * m.options.up;
  }
  if (m.options.scenario == Scenario::kWind) {
    const double gust = 1 + kGustFraction * std::sin(2 * kPi * kGustHz * t);
    env.air_velocity_m_s = head_from_world * (Ramp(t) * gust * m.options.wind_m_s);
  }
  return env;
}

Status HairSimulationOptions::Check() const {
  HR_RETURN_IF_ERROR(material.Check().WithContext("material"));
  HR_RETURN_IF_ERROR(dynamics.Check().WithContext("dynamics"));
  if (!up.allFinite() || std::abs(up.norm() - 1) > 1e-6)
    return InvalidArgument("up must be a unit vector");
  if (has_head && (!head_radii_mm.allFinite() || !(head_radii_mm.minCoeff() > 0)))
    return InvalidArgument("head_radii_mm must be finite and positive");
  if (has_head && !head_center_mm.allFinite())
    return InvalidArgument("head_center_mm must be finite");
  if (!std::isfinite(shake_amplitude_deg))
    return InvalidArgument("shake_amplitude_deg must be finite");
  if (!std::isfinite(shake_frequency_hz) || shake_frequency_hz < 0)
    return InvalidArgument("shake_frequency_hz must be finite and >= 0");
  if (!wind_m_s.allFinite()) return InvalidArgument("wind_m_s must be finite");
  if (threads < 0) return InvalidArgument("threads must be 0 (one per core) or more");
  return Status::Ok();
}

Result<std::unique_ptr<HairSimulation>> HairSimulation::Create(
    const HelixModel& model, const HairSimulationOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("simulation options"));
  if (model.guides.empty()) return InvalidArgument("simulation: the model has no guide strand");
  DynamicsOptions dynamics_options = options.dynamics;
  if (options.has_head) {
    dynamics_options.use_head = true;
    dynamics_options.head.center_m = 1e-3 * options.head_center_mm;
    dynamics_options.head.radii_m = 1e-3 * options.head_radii_mm;
    dynamics_options.head_surface = options.head_surface;
  }
  HR_RETURN_IF_ERROR(dynamics_options.Check().WithContext("simulation options: dynamics"));
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->options.dynamics = dynamics_options;
  std::unique_ptr<HairSimulation> sim(new HairSimulation(std::move(impl)));
  Impl& m = *sim->impl_;
  const Environment at_rest = sim->EnvironmentAt(0);
  m.dynamics.reserve(model.guides.size());
  for (size_t g = 0; g < model.guides.size(); ++g) {
    Eigen::VectorXd q;
    auto strand = SuperHelixFromPiecewiseHelix(model.guides[g], options.up, &q);
    if (!strand.ok())
      return InvalidArgument("guide " + std::to_string(g) + ": " + strand.status().message());
    m.dynamics.emplace_back(*strand, options.material, dynamics_options);
    if (options.contact_from_rest) m.dynamics.back().HoldContactAtRest(q);
    if (options.inverse_statics) {
      InverseStaticsReport report;
      HR_RETURN_IF_ERROR(SolveInverseStatics(at_rest, q, &m.dynamics.back(), &report));
      m.stats.max_inverse_statics_change =
          std::max(m.stats.max_inverse_statics_change, report.max_rest_change);
    }
    m.states.push_back({q, Eigen::VectorXd::Zero(q.size())});
  }
  return sim;
}

HairSimulation::HairSimulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HairSimulation::~HairSimulation() = default;

// Guides do not interact, so each guide is stepped through the whole
// interval by one thread.
Status HairSimulation::Advance(double seconds) {
  Impl& m = *impl_;
  const double dt = m.options.dynamics.time_step_s;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  std::vector<Environment> environments;
  for (int k = 0; k < steps; ++k) environments.push_back(EnvironmentAt(m.time_s + k * dt));
  const size_t guides = static_cast<size_t>(num_guides());
  std::vector<Status> statuses(guides);
  std::vector<long long> contacts(guides, 0), iterations(guides, 0);
  ParallelFor(guides, ResolveThreads(m.options.threads), [&] {
    return [&](size_t g) {
      for (int k = 0; k < steps; ++k) {
        StepReport report;
        statuses[g] =
            m.dynamics[g].Step(environments[static_cast<size_t>(k)], &m.states[g], &report);
        if (!statuses[g].ok()) break;
        contacts[g] += report.contacts;
        iterations[g] += report.solver_iterations;
      }
    };
  });
  m.time_s += steps * dt;
  m.stats.steps += steps;
  m.stats.contact_samples += std::accumulate(contacts.begin(), contacts.end(), 0LL);
  m.solver_iterations += std::accumulate(iterations.begin(), iterations.end(), 0LL);
  m.stats.mean_solver_iterations =
      static_cast<double>(m.solver_iterations) /
      static_cast<double>(std::max<long long>(1, m.stats.steps * static_cast<long long>(guides)));
  for (size_t g = 0; g < guides; ++g) {
    if (!statuses[g].ok()) return statuses[g].WithContext("guide " + std::to_string(g));
  }
  return Status::Ok();
}

double HairSimulation::time_s() const { return impl_->time_s; }
int HairSimulation::num_guides() const { return static_cast<int>(impl_->dynamics.size()); }
const HairSimulationStats& HairSimulation::stats() const { return impl_->stats; }
Eigen::Matrix3d HairSimulation::head_rotation() const { return impl_->HeadRotation(impl_->time_s); }

Eigen::Vector3d HairSimulation::head_translation_mm() const {
  const Eigen::Vector3d pivot = impl_->PivotMm();
  return pivot - head_rotation() * pivot;
}

std::vector<std::vector<Eigen::Vector3d>> HairSimulation::GuideCurves(int per_element) const {
  const Eigen::Matrix3d rotation = head_rotation();
  const Eigen::Vector3d translation = head_translation_mm();
  std::vector<std::vector<Eigen::Vector3d>> curves;
  for (size_t g = 0; g < impl_->dynamics.size(); ++g) {
    std::vector<Eigen::Vector3d> curve =
        Centreline(impl_->dynamics[g].strand(), impl_->states[g].q, per_element);
    for (Eigen::Vector3d& p : curve) p = rotation * (1e3 * p) + translation;
    curves.push_back(std::move(curve));
  }
  return curves;
}

}  // namespace hairrig
