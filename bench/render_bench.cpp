// Render time per 1200 x 1600 view. Run from the repository root:
//   build/bench/hairrig_bench --benchmark_filter=Render
// BM_RenderView/<scene>/<threads>: scene 0 = etc/scenes/default.yaml (a
// 40,000-strand wig in wisps on the mannequin head, Marschner shading, deep
// opacity shadows), 1 = etc/scenes/curly_blond.yaml (50,000 strands), 2 = the
// simulated subject as it was before the mannequin (the default rig with an
// ellipsoid head, 10,000 independent strands, Kajiya-Kay shading, no shadows),
// for the ratio in one run, 3 = the default scene's wig with 50,000 strands.
// BM_RenderNoHair: the same views without the hair.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <stdexcept>

#include "sim_hw/renderer.h"

namespace hairrig {
namespace {

Scene LoadOrThrow(const std::string& path) {
  auto scene = LoadScene(path);
  if (!scene.ok()) throw std::runtime_error(scene.status().ToString());
  return *scene;
}

Scene SceneFor(int which) {
  if (which == 1) return LoadOrThrow("etc/scenes/curly_blond.yaml");
  Scene scene = LoadOrThrow("etc/scenes/default.yaml");
  if (which == 3) scene.wig.num_strands = 50000;
  if (which == 2) {
    scene.head = HeadSpec{};
    scene.head.center_turntable_mm = Eigen::Vector3d(0, 0, 330);
    scene.wig = WigOptions{};
    scene.wig.min_length_mm = 150;
    scene.wig.max_length_mm = 260;
    scene.hair_shading.model = HairShading::Model::kKajiyaKay;
    scene.hair_shading.shadows = false;
  }
  return scene;
}

const Renderer& RendererFor(int which) {
  static std::map<int, std::unique_ptr<Renderer>> renderers;
  auto& r = renderers[which];
  if (!r) {
    auto created = Renderer::Create(SceneFor(which));
    if (!created.ok()) throw std::runtime_error(created.status().ToString());
    r = std::move(created).value();
  }
  return *r;
}

void Run(benchmark::State& state, bool draw_hair) {
  const Renderer& renderer = RendererFor(static_cast<int>(state.range(0)));
  RenderOptions options;
  options.draw_hair = draw_hair;
  options.threads = static_cast<int>(state.range(1));
  int view = 0;
  for (auto _ : state) {
    auto v = renderer.Render(view % 2, 18.947 * (view / 2), options);
    benchmark::DoNotOptimize(v);
    ++view;
  }
  state.counters["strands"] =
      static_cast<double>(draw_hair ? renderer.strands_turntable_mm().num_strands() : 0);
}

void BM_RenderView(benchmark::State& state) { Run(state, true); }
void BM_RenderNoHair(benchmark::State& state) { Run(state, false); }
BENCHMARK(BM_RenderView)
    ->Args({0, 2})
    ->Args({0, 1})
    ->Args({1, 2})
    ->Args({3, 2})
    ->Args({2, 2})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RenderNoHair)->Args({0, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hairrig

BENCHMARK_MAIN();
