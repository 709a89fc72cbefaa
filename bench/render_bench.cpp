// Render time per view of the default scene (1200 x 1600, 10,000 strands), one
// thread, and its parts. Run: build/bench/hairrig_bench --benchmark_filter=Render
#include <benchmark/benchmark.h>

#include "sim_hw/renderer.h"

namespace hairrig {
namespace {

const Renderer& DefaultRenderer() {
  static std::unique_ptr<Renderer> renderer = [] {
    auto scene = LoadScene("etc/scenes/default.yaml");
    if (!scene.ok()) throw std::runtime_error(scene.status().ToString());
    auto r = Renderer::Create(*scene);
    if (!r.ok()) throw std::runtime_error(r.status().ToString());
    return std::move(r).value();
  }();
  return *renderer;
}

void BM_RenderView(benchmark::State& state) {
  const Renderer& renderer = DefaultRenderer();
  RenderOptions options;
  options.draw_hair = state.range(0) != 0;
  int view = 0;
  for (auto _ : state) {
    auto v = renderer.Render(view % 2, 18.947 * (view / 2), options);
    benchmark::DoNotOptimize(v);
    ++view;
  }
  state.counters["strands"] = static_cast<double>(options.draw_hair ? renderer.strands_turntable_mm().num_strands() : 0);
}
BENCHMARK(BM_RenderView)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hairrig

BENCHMARK_MAIN();
