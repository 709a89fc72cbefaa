// The hair segmentation (reconstruction/hair_segmentation.h) on every view of
// a simulated capture, against the renderer's labels. Run from the repository
// root:
//   build/bench/hairrig_segmentation_bench CAPTURE [--colour-components K]
//       [--texture-feature yes|no] [--texture-less-noise yes|no] [--skin-chromaticity SIGMAS]
//       [--skin-chromaticity-log-ratio R] [--capture-skin yes|no]
//       [--capture-skin-touching-outline yes|no] [--views 0,1,...]
//       [--opaque-shadow-as-skin yes|no] [--opaque-shadow-touching-skin-only yes|no]
//       [--outline-blend SIGMAS] [--clipped-level L]
//       [--texture-sigma PX] [--threads T] [--pictures DIR]
// CAPTURE is a folder from `hairrig capture --out CAPTURE --calibrate`. Prints
// each view's hair IoU and which true labels the errors fall on (skin taken
// for hair, hair taken for backdrop or skin), the median and worst IoU, and
// the time per view, and what the true bare skin was labelled over all views
// (the growth's skin tests see only what is labelled skin). The views are segmented as the points
// stage does (SegmentCaptureViews: views with too little skin of their own, or whose own does not
// agree with the others', borrow the capture's skin model); --capture-skin no segments each view
// alone, --capture-skin-touching-outline no keeps every region the capture's model turns to skin,
// not only those that reach the subject's outline. --pictures writes each view with its
// errors painted: red where skin or backdrop is taken for hair, blue where hair is missed, and
// its labels (reconstruction/hair_segmentation.h, kSeg*) as a PNG.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_args.h"
#include "core/image_file.h"
#include "core/parallel.h"
#include "core/truth_maps.h"
#include "reconstruction/evaluation.h"
#include "reconstruction/hair_segmentation.h"
#include "rig/reconstruction_input.h"

namespace {

using namespace hairrig;

struct ViewRow {
  std::string name;
  double iou = 0;
  int skin_as_hair = 0, backdrop_as_hair = 0, hair_as_skin = 0, hair_as_backdrop = 0;
  int skin = 0, skin_as_skin = 0, skin_as_backdrop = 0;  // the true bare skin and what it got
  bool capture_skin = false;
  int64_t capture_skin_pixels = 0;
};

Result<ViewRow> ScoreView(const ReconstructionView& view, const cv::Mat& image,
                          const HairSegmentation& seg, const CaptureTruth& truth,
                          const std::string& pictures) {
  HR_ASSIGN_OR_RETURN(const ViewTruthMaps maps, ReadViewTruthMaps(truth.views_dir, view.id));
  const cv::Mat hair = seg.label == kSegHair, true_hair = maps.label == ViewTruthMaps::kHair;
  ViewRow row;
  row.name = view.name;
  HR_ASSIGN_OR_RETURN(row.iou, MaskIoU(hair, true_hair));
  row.skin_as_hair = cv::countNonZero(hair & (maps.label == ViewTruthMaps::kHead));
  row.backdrop_as_hair = cv::countNonZero(hair & (maps.label == ViewTruthMaps::kBackdrop));
  row.hair_as_skin = cv::countNonZero(true_hair & (seg.label == kSegHead));
  row.hair_as_backdrop = cv::countNonZero(true_hair & (seg.label == kSegBackdrop));
  const cv::Mat true_skin = maps.label == ViewTruthMaps::kHead;
  row.skin = cv::countNonZero(true_skin);
  row.skin_as_skin = cv::countNonZero(true_skin & (seg.label == kSegHead));
  row.skin_as_backdrop = cv::countNonZero(true_skin & (seg.label == kSegBackdrop));
  row.capture_skin = seg.used_capture_skin;
  row.capture_skin_pixels = seg.capture_skin_pixels;
  if (!pictures.empty()) {
    cv::Mat painted = image.clone();
    painted.setTo(cv::Scalar(0, 0, 255), hair & ~true_hair);
    painted.setTo(cv::Scalar(255, 0, 0), true_hair & ~hair);
    HR_RETURN_IF_ERROR(WriteImageAtomic(pictures + "/" + view.name + "_errors.jpg", painted));
    HR_RETURN_IF_ERROR(WriteImageAtomic(pictures + "/" + view.name + "_labels.png", seg.label));
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: %s CAPTURE [--colour-components K] [--texture-feature yes|no] "
        "[--skin-chromaticity SIGMAS] [--skin-chromaticity-log-ratio R] "
        "[--capture-skin yes|no] [--capture-skin-touching-outline yes|no] [--views 0,1,...] "
        "[--opaque-shadow-as-skin yes|no] [--opaque-shadow-touching-skin-only yes|no] "
        "[--outline-blend SIGMAS] [--clipped-level L] "
        "[--texture-sigma PX] [--threads T] "
        "[--pictures DIR]\n",
        argv[0]);
    return 2;
  }
  const std::string capture = argv[1];
  SegmentationOptions options;
  int threads = 2;
  std::string pictures;
  std::vector<int> views;
  if (argc % 2 != 0) {
    std::fprintf(stderr, "%s: every option takes a value\n", argv[argc - 1]);
    return 2;
  }
  for (int i = 2; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--colour-components") == 0) {
      options.colour_components = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--texture-feature") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.texture_feature)) return 2;
    } else if (std::strcmp(argv[i], "--texture-less-noise") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.texture_less_noise)) return 2;
    } else if (std::strcmp(argv[i], "--skin-chromaticity") == 0) {
      options.skin_chromaticity_sigmas = std::atof(argv[i + 1]);  // 0: off
    } else if (std::strcmp(argv[i], "--skin-chromaticity-log-ratio") == 0) {
      options.skin_chromaticity_log_ratio = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--capture-skin") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.capture_skin)) return 2;
    } else if (std::strcmp(argv[i], "--capture-skin-touching-outline") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.capture_skin_touching_outline)) return 2;
    } else if (std::strcmp(argv[i], "--opaque-shadow-as-skin") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.opaque_shadow_as_skin)) return 2;
    } else if (std::strcmp(argv[i], "--opaque-shadow-touching-skin-only") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.opaque_shadow_touching_skin_only)) return 2;
    } else if (std::strcmp(argv[i], "--outline-blend") == 0) {
      options.outline_blend_sigmas = std::atof(argv[i + 1]);  // 0: off
    } else if (std::strcmp(argv[i], "--clipped-level") == 0) {
      options.clipped_level = std::atoi(argv[i + 1]);  // 0: off
    } else if (std::strcmp(argv[i], "--texture-sigma") == 0) {
      options.texture_sigma_px = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--views") == 0) {
      std::stringstream list(argv[i + 1]);
      for (std::string id; std::getline(list, id, ',');) views.push_back(std::atoi(id.c_str()));
    } else if (std::strcmp(argv[i], "--pictures") == 0) {
      pictures = argv[i + 1];
      std::filesystem::create_directories(pictures);
    } else if (std::strcmp(argv[i], "--threads") == 0) {
      threads = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  auto input = LoadCaptureReconstructionInput(capture);
  auto truth = ReadCaptureTruth(capture);
  if (!input.ok() || !truth.ok()) {
    std::fprintf(stderr, "%s\n",
                 (!input.ok() ? input.status() : truth.status()).ToString().c_str());
    return 1;
  }
  if (const Status selected = SelectViews(views, &*input); !selected.ok()) {
    std::fprintf(stderr, "%s\n", selected.ToString().c_str());
    return 2;
  }
  if (input->views.empty()) {
    std::fprintf(stderr, "%s: no view to segment\n", capture.c_str());
    return 1;
  }
  const size_t count = input->views.size();
  std::vector<ViewRow> rows(count);
  std::vector<std::string> errors;
  std::mutex mutex;
  const auto report = [&](size_t k, const Status& status) {
    const std::lock_guard<std::mutex> lock(mutex);
    errors.push_back(input->views[k].name + ": " + status.ToString());
  };
  std::vector<cv::Mat> images(count);
  ParallelFor(count, threads, [&] {
    return [&](size_t k) {
      Result<cv::Mat> image = ReadImageFile(input->views[k].image_path, cv::IMREAD_COLOR);
      if (image.ok())
        images[k] = *std::move(image);
      else
        report(k, image.status());
    };
  });
  if (!errors.empty()) {
    for (const std::string& e : errors) std::fprintf(stderr, "%s\n", e.c_str());
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Result<HairSegmentation>> segmented =
      SegmentCaptureViews(count, options, threads, [&](size_t k, const SkinChromaticity* skin) {
        return SegmentHair(images[k], input->views[k].not_hair_px, options, skin);
      });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ParallelFor(count, threads, [&] {
    return [&](size_t k) {
      Result<ViewRow> row =
          segmented[k].ok() ? ScoreView(input->views[k], images[k], *segmented[k], *truth, pictures)
                            : Result<ViewRow>(segmented[k].status());
      if (row.ok())
        rows[k] = *row;
      else
        report(k, row.status());
    };
  });
  for (const std::string& e : errors) std::fprintf(stderr, "%s\n", e.c_str());
  if (!errors.empty()) return 1;
  std::printf("%-22s %6s %12s %14s %12s %14s %14s\n", "view", "IoU", "skin->hair", "backdrop->hair",
              "hair->skin", "hair->backdrop", "capture skin");
  std::vector<double> ious;
  int64_t skin = 0, skin_as_skin = 0, skin_as_hair = 0, skin_as_backdrop = 0;
  for (const ViewRow& r : rows) {
    skin += r.skin;
    skin_as_skin += r.skin_as_skin;
    skin_as_hair += r.skin_as_hair;
    skin_as_backdrop += r.skin_as_backdrop;
    std::printf("%-22s %6.3f %12d %14d %12d %14d %14s\n", r.name.c_str(), r.iou, r.skin_as_hair,
                r.backdrop_as_hair, r.hair_as_skin, r.hair_as_backdrop,
                r.capture_skin ? std::to_string(r.capture_skin_pixels).c_str() : "-");
    ious.push_back(r.iou);
  }
  std::sort(ious.begin(), ious.end());
  std::printf(
      "hair IoU over %zu views: median %.3f, worst %.3f, mean %.3f; %.2f s per view on %d "
      "threads\n",
      ious.size(), ious[ious.size() / 2], ious.front(),
      std::accumulate(ious.begin(), ious.end(), 0.0) / static_cast<double>(ious.size()),
      seconds / static_cast<double>(ious.size()), threads);
  const auto share = [&](int64_t n) {
    return 100.0 * static_cast<double>(n) / static_cast<double>(std::max<int64_t>(1, skin));
  };
  std::printf("true bare skin (%lld px): labelled skin %.1f %%, hair %.1f %%, backdrop %.1f %%\n",
              static_cast<long long>(skin), share(skin_as_skin), share(skin_as_hair),
              share(skin_as_backdrop));
  return 0;
}
