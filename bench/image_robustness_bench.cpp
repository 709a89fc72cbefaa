// The reconstruction's image stages (hair segmentation, 2D orientation maps)
// under every scene variation of sim_hw/scene_variations.h, against the
// simulated rig's ground truth. Run from the repository root:
//   build/bench/hairrig_image_robustness_bench [--scene F]... [--vary a,b]... [--views N]
//       [--scales S] [--smoothing PX] [--pictures DIR]
// Scenes default to etc/scenes/default.yaml and etc/scenes/curly_blond.yaml;
// variations to none and each of the library's, one at a time (--vary a+b
// combines). For each, N views spread over both cameras and the turntable
// (default 3) are rendered and scored: hair mask IoU of the segmentation, and
// the orientation map's median error (deg) on the true hair the segmentation
// kept, at confidence >= 0.2, with the share of those pixels kept (--scales:
// the orientation map's pyramid, OrientationOptions::scales; --smoothing: its
// smoothing_px). Prints one
// Markdown table per scene. --pictures writes each variation's first view.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/calib_box.h"
#include "core/image_file.h"
#include "core/truth_maps.h"
#include "reconstruction/evaluation.h"
#include "reconstruction/hair_segmentation.h"
#include "reconstruction/orientation_map.h"
#include "sim_hw/renderer.h"
#include "sim_hw/scene_variations.h"

namespace {

using namespace hairrig;

struct Score {
  double iou = 0, orientation_median_deg = 0, kept = 0;
  int views = 0;
};

std::vector<std::string> SplitOn(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

// The calibration box's outline in a view: what the rig tells the segmentation holds no hair.
std::vector<std::vector<cv::Point2f>> BoxOutline(const Scene& scene, int camera, double deg) {
  const SceneCamera& cam = scene.cameras[static_cast<size_t>(camera)];
  const Rigid3d cam_from_box =
      cam.cam_from_world * WorldFromTurntable(deg) * scene.turntable_from_box;
  const auto corners = BoxCornerPoints(0.5 * scene.box.size_mm);
  return {ProjectedOutline(cam.intrinsics, cam_from_box, {corners.begin(), corners.end()})};
}

struct BenchOptions {
  int views = 3;
  OrientationOptions orientation;
  std::string pictures;
};

Result<Score> ScoreVariation(const Scene& base, const std::string& variation,
                             const BenchOptions& options) {
  const int views = options.views;
  const std::string& pictures = options.pictures;
  Scene scene = base;
  HR_RETURN_IF_ERROR(ApplySceneVariations(SplitOn(variation, '+'), &scene));
  HR_ASSIGN_OR_RETURN(const auto renderer, Renderer::Create(scene));
  Score score;
  for (int i = 0; i < views; ++i) {
    const int camera = i % static_cast<int>(scene.cameras.size());
    const double deg = scene.StopAngleDeg((i * scene.turntable_stops) / views);
    RenderOptions ro;
    ro.ground_truth = true;
    ro.noise_seed = static_cast<uint64_t>(i + 1);
    HR_ASSIGN_OR_RETURN(const RenderedView view, renderer->Render(camera, deg, ro));
    if (i == 0 && !pictures.empty()) {
      HR_RETURN_IF_ERROR(WriteImageAtomic(
          pictures + "/" + scene.name + "_" + (variation.empty() ? "none" : variation) + ".png",
          view.image));
    }
    const cv::Mat true_hair = view.truth.label == ViewTruthMaps::kHair;
    HR_ASSIGN_OR_RETURN(const HairSegmentation seg,
                        SegmentHair(view.image, BoxOutline(scene, camera, deg), {}));
    const cv::Mat hair = seg.label == kSegHair;
    HR_ASSIGN_OR_RETURN(const double iou, MaskIoU(hair, true_hair));
    HR_ASSIGN_OR_RETURN(const OrientationMap map,
                        ComputeOrientationMap(view.image, hair, options.orientation));
    HR_ASSIGN_OR_RETURN(const OrientationAccuracy o,
                        MeasureOrientation(map, view.truth.orientation_deg, hair & true_hair, 0.2));
    score.iou += iou / views;
    score.orientation_median_deg += o.median_error_deg / views;
    score.kept += o.kept_fraction / views;
    ++score.views;
  }
  return score;
}

int Run(const std::vector<std::string>& scenes, std::vector<std::string> variations,
        const BenchOptions& options) {
  if (variations.empty()) {
    variations.push_back("");
    for (const SceneVariation& v : SceneVariations()) variations.push_back(v.name);
  }
  for (const std::string& path : scenes) {
    auto scene = LoadScene(path);
    if (!scene.ok()) {
      std::fprintf(stderr, "%s\n", scene.status().ToString().c_str());
      return 1;
    }
    std::printf("\n%s (%d views, orientation scales %d, smoothing %.1f px)\n\n", path.c_str(),
                options.views, options.orientation.scales, options.orientation.smoothing_px);
    std::printf("| variation | hair IoU | orientation median (deg) | kept at conf >= 0.2 |\n");
    std::printf("| --- | --- | --- | --- |\n");
    for (const std::string& variation : variations) {
      auto score = ScoreVariation(*scene, variation, options);
      const char* name = variation.empty() ? "none" : variation.c_str();
      if (!score.ok()) {
        std::printf("| %s | failed: %s | | |\n", name, score.status().ToString().c_str());
        continue;
      }
      std::printf("| %s | %.3f | %.1f | %.0f %% |\n", name, score->iou,
                  score->orientation_median_deg, 100 * score->kept);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> scenes, variations;
  BenchOptions options;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--scene") == 0 && has_value) {
      scenes.push_back(argv[++i]);
    } else if (std::strcmp(argv[i], "--vary") == 0 && has_value) {
      for (const std::string& v : SplitOn(argv[++i], ','))
        variations.push_back(v == "none" ? "" : v);
    } else if (std::strcmp(argv[i], "--views") == 0 && has_value) {
      options.views = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--scales") == 0 && has_value) {
      options.orientation.scales = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--smoothing") == 0 && has_value) {
      options.orientation.smoothing_px = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--pictures") == 0 && has_value) {
      options.pictures = argv[++i];
      std::filesystem::create_directories(options.pictures);
    } else {
      std::fprintf(stderr,
                   "usage: %s [--scene F]... [--vary a,b+c,...] [--views N] [--scales S] "
                   "[--smoothing PX] [--pictures DIR]\n",
                   argv[0]);
      return 2;
    }
  }
  if (scenes.empty()) scenes = {"etc/scenes/default.yaml", "etc/scenes/curly_blond.yaml"};
  return Run(scenes, variations, options);
}
