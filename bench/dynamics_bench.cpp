// Super-helix dynamics speed (run from the repository root):
//   build/bench/hairrig_dynamics_bench [steps]
// Guides of the simulated rig's wavy wig (default scene head, head contact on,
// head-shake scenario, time step 1/240 s), fitted with a fixed element count N,
// stepped by HairSimulation. Rows: how steps per second grow with N and with
// the number of guides; the paper's conjugate gradient beside Cholesky; one
// thread beside all cores.
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "sim_hw/scene.h"
#include "sim_hw/wig.h"
#include "simulation/hair_simulation.h"

using namespace hairrig;

namespace {

Result<HelixModel> Hairstyle(const SceneHead& head, int guides, int elements) {
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

void Row(const SceneHead& head, int guides, int elements, LinearSolver solver, int threads, int steps) {
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
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%7d %9d %-9s %8d %12.1f %14.1f %11.1f\n", guides, elements,
              solver == LinearSolver::kConjugateGradient ? "cg" : "cholesky", threads, steps / seconds,
              steps * guides / seconds / 1000, (*sim)->stats().mean_solver_iterations);
}

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 24;
  const SceneHead head;
  std::printf("%7s %9s %-9s %8s %12s %14s %11s\n", "guides", "elements", "solver", "threads", "steps/s",
              "kguide-steps/s", "iterations");
  for (LinearSolver solver : {LinearSolver::kConjugateGradient, LinearSolver::kCholesky}) {
    Row(head, 1000, 15, solver, 0, steps);
  }
  Row(head, 1000, 15, LinearSolver::kCholesky, 1, steps);
  for (int elements : {5, 10, 25}) Row(head, 1000, elements, LinearSolver::kCholesky, 0, steps);
  for (int guides : {100, 300, 3000}) Row(head, guides, 15, LinearSolver::kCholesky, 0, steps);
  return 0;
}
