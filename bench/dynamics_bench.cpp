// Super-helix dynamics speed (run from the repository root):
//   build/bench/hairrig_dynamics_bench [steps]
// Guides of the simulated rig's wavy wig (default scene head, head contact on,
// head-shake scenario, time step 1/240 s), fitted with a fixed element count N,
// stepped by HairSimulation. Rows: how steps per second grow with N and with
// the number of guides; the paper's conjugate gradient beside Cholesky; one
// thread beside all cores. Last, guide-to-full interpolation: 1,000 guides
// driving 40,000 strands, the time to build the weights and per frame.
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "sim_hw/scene.h"
#include "sim_hw/wig.h"
#include "simulation/guide_interpolation.h"
#include "simulation/hair_simulation.h"

using namespace hairrig;

namespace {

Result<HelixModel> Hairstyle(const HeadSpec& head, int guides, int elements) {
  WigOptions wig;
  wig.num_strands = guides;
  wig.min_length_mm = 150;
  wig.max_length_mm = 250;
  HR_ASSIGN_OR_RETURN(StrandSet strands, GenerateWig(wig, head));
  FitOptions fit;
  fit.guides.num_guides = guides;
  fit.fitting.adaptive = false;
  fit.fitting.fixed_elements = elements;
  FitSummary summary;
  return FitHairModel(strands, fit, &summary);
}

void Row(const HeadSpec& head, int guides, int elements, LinearSolver solver, int threads,
         int steps) {
  auto model = Hairstyle(head, guides, elements);
  if (!model.ok()) {
    std::fprintf(stderr, "%s\n", model.status().ToString().c_str());
    std::exit(1);
  }
  HairSimulationOptions o;
  o.scenario = Scenario::kHeadShake;
  o.has_head = true;
  o.head_center_mm = head.center_turntable_mm;
  o.head_radii_mm = head.radii_mm;
  o.dynamics.solver = solver;
  o.threads = threads;
  auto sim = HairSimulation::Create(*model, o);
  if (!sim.ok() || !(*sim)->Advance(2 * o.dynamics.time_step_s).ok()) std::exit(1);
  const auto start = std::chrono::steady_clock::now();
  if (!(*sim)->Advance(steps * o.dynamics.time_step_s).ok()) std::exit(1);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%7d %9d %-9s %8d %12.1f %14.1f %11.1f\n", guides, elements,
              solver == LinearSolver::kConjugateGradient ? "cg" : "cholesky", threads,
              steps / seconds, steps * guides / seconds / 1000,
              (*sim)->stats().mean_solver_iterations);
}

void Interpolation(const HeadSpec& head) {
  WigOptions wig;
  wig.num_strands = 40000;
  auto full = GenerateWig(wig, head);
  if (!full.ok()) std::exit(1);
  FitOptions fit;
  fit.guides.num_guides = 1000;
  fit.fitting.adaptive = false;
  fit.fitting.fixed_elements = 15;
  FitSummary summary;
  auto model = FitHairModel(*full, fit, &summary);
  if (!model.ok()) std::exit(1);
  HairSimulationOptions o;
  o.has_head = true;
  o.head_center_mm = head.center_turntable_mm;
  o.head_radii_mm = head.radii_mm;
  auto sim = HairSimulation::Create(*model, o);
  if (!sim.ok()) std::exit(1);
  const auto rest = (*sim)->GuideCurves(4);
  auto start = std::chrono::steady_clock::now();
  auto interpolation = GuideInterpolation::Build(*full, rest, {});
  if (!interpolation.ok()) std::exit(1);
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  start = std::chrono::steady_clock::now();
  if (!interpolation->Apply(rest).ok()) std::exit(1);
  const double apply_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "interpolation: 1000 guides -> %zu strands (%zu points): weights %.2f s, %.3f s per frame, "
      "rest fit RMS %.2f mm\n",
      full->num_strands(), full->num_points(), build_s, apply_s, interpolation->rest_fit_rms_mm());
}

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 24;
  const HeadSpec head;
  std::printf("%7s %9s %-9s %8s %12s %14s %11s\n", "guides", "elements", "solver", "threads",
              "steps/s", "kguide-steps/s", "iterations");
  for (LinearSolver solver : {LinearSolver::kConjugateGradient, LinearSolver::kCholesky}) {
    Row(head, 1000, 15, solver, 0, steps);
  }
  Row(head, 1000, 15, LinearSolver::kCholesky, 1, steps);
  for (int elements : {5, 10, 25}) Row(head, 1000, elements, LinearSolver::kCholesky, 0, steps);
  for (int guides : {100, 300, 3000}) Row(head, guides, 15, LinearSolver::kCholesky, 0, steps);
  Interpolation(head);
  return 0;
}
