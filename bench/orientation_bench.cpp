// 2D orientation maps against the simulated rig's ground truth, per variant
// of the filter bank. Run from the repository root:
//   build/bench/hairrig_orientation_bench [scene.yaml ...] [--views N]
// For each scene, N views (default 4, spread over the turntable) are rendered
// with their ground-truth maps; each variant's map is scored on the true hair
// pixels (label hair): median and 90th-percentile angle error of the pixels
// kept at confidence >= 0.2 (and at 0), the share kept, and the time per view.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/statistics.h"
#include "reconstruction/evaluation.h"
#include "reconstruction/orientation_map.h"
#include "sim_hw/renderer.h"

namespace {

using namespace hairrig;

struct Variant {
  const char* name;
  OrientationOptions options;
};

std::vector<Variant> Variants() {
  std::vector<Variant> v;
  v.push_back({"the default (quadrature, 3 scales, smoothing 2 px)", OrientationOptions()});
  // The bank's own variants, on the image alone and unsmoothed.
  OrientationOptions o;
  o.scales = 1;
  o.smoothing_px = 0;
  o.refinement_passes = 0;
  o.quadrature = false;
  v.push_back({"even, no refinement", o});
  o.refinement_passes = 2;
  v.push_back({"even, 2 refinements (Luo 2012 + Chai 2012)", o});
  o.quadrature = true;
  o.refinement_passes = 0;
  v.push_back({"quadrature, no refinement", o});
  o.refinement_passes = 1;
  v.push_back({"quadrature, 1 refinement", o});
  o.refinement_passes = 0;
  o.directions = 16;
  v.push_back({"quadrature, 16 directions", o});
  o.directions = 32;
  o.sigma_along_px = 5;
  v.push_back({"quadrature, along 5", o});
  o.sigma_along_px = 8;
  v.push_back({"quadrature, along 8", o});
  o.sigma_across_px = 2.5, o.wavelength_px = 6;
  v.push_back({"quadrature, along 8 across 2.5 wave 6", o});
  o.sigma_across_px = 1.2, o.wavelength_px = 3;
  v.push_back({"quadrature, along 8 across 1.2 wave 3", o});
  return v;
}

int Run(const std::vector<std::string>& scenes, int views) {
  for (const std::string& path : scenes) {
    auto scene = LoadScene(path);
    if (!scene.ok()) {
      std::fprintf(stderr, "%s\n", scene.status().ToString().c_str());
      return 1;
    }
    auto renderer = Renderer::Create(*scene);
    if (!renderer.ok()) {
      std::fprintf(stderr, "%s\n", renderer.status().ToString().c_str());
      return 1;
    }
    std::printf("%s\n", path.c_str());
    {
      // How much the truth itself varies between hair pixels 2 px apart: the
      // front-most strand changes from pixel to pixel inside a wisp.
      RenderOptions ro;
      ro.ground_truth = true;
      auto view = (*renderer)->Render(0, scene->StopAngleDeg(0), ro);
      if (!view.ok()) return 1;
      std::vector<double> differences;
      const cv::Mat1f& t = view->truth.orientation_deg;
      for (int y = 0; y < t.rows; ++y) {
        for (int x = 0; x + 2 < t.cols; ++x) {
          if (std::isfinite(t(y, x)) && std::isfinite(t(y, x + 2)))
            differences.push_back(OrientationDifferenceDeg(t(y, x), t(y, x + 2)));
        }
      }
      if (!differences.empty()) {
        std::printf("  the truth between hair pixels 2 px apart: median %.2f deg, p90 %.2f deg\n",
                    Median(differences), Quantile(differences, 0.9));
      }
    }
    for (const Variant& variant : Variants()) {
      double median = 0, p90 = 0, kept = 0, median_all = 0, seconds = 0;
      for (int i = 0; i < views; ++i) {
        RenderOptions ro;
        ro.ground_truth = true;
        const int stops = scene->turntable_stops;
        const int stop = (i * stops) / views;
        auto view = (*renderer)->Render(i % static_cast<int>(scene->cameras.size()),
                                        scene->StopAngleDeg(stop), ro);
        if (!view.ok()) return 1;
        const cv::Mat hair = view->truth.label == ViewTruthMaps::kHair;
        const auto t0 = std::chrono::steady_clock::now();
        auto map = ComputeOrientationMap(view->image, hair, variant.options);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (!map.ok()) return 1;
        const auto kept_02 = MeasureOrientation(*map, view->truth.orientation_deg, hair, 0.2);
        const cv::Mat dense = hair & (view->truth.hair_alpha >= 0.95f);
        const auto all = MeasureOrientation(*map, view->truth.orientation_deg, dense, 0.0);
        median += kept_02->median_error_deg / views;
        p90 += kept_02->p90_error_deg / views;
        kept += kept_02->kept_fraction / views;
        median_all += all->median_error_deg / views;
      }
      std::printf(
          "  %-44s median %5.2f deg  p90 %5.2f deg  kept %4.1f %%  (coverage >= 0.95: median "
          "%5.2f)  %.2f s/view\n",
          variant.name, median, p90, 100 * kept, median_all, seconds / views);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> scenes;
  int views = 4;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--views") == 0 && i + 1 < argc)
      views = std::max(1, std::atoi(argv[++i]));
    else
      scenes.push_back(argv[i]);
  }
  if (scenes.empty()) scenes = {"etc/scenes/default.yaml"};
  return Run(scenes, views);
}
