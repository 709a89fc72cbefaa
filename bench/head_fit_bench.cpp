// The head fit (reconstruction/head_fit.h) on a capture of the simulated rig
// whose points stage has run, against the true head the ground truth
// records. Run from the repository root:
//   build/bench/hairrig_head_fit_bench CAPTURE [--labels reconstruction|truth]
//       [--hair-weight W] [--prior-samples N] [--skin-scale MM]
// --labels truth fits to the renderer's own labels instead of the
// segmentation's, so that the method's error and the segmentation's part
// in it are measured apart. Prints the fit, its errors against the true
// head's ellipsoid (a skull-sized one the rig config gives beside the
// mannequin's mesh) and face direction, and the time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/head_model.h"
#include "core/truth_maps.h"
#include "reconstruction/head_fit.h"
#include "rig/reconstruction_input.h"

namespace {

using namespace hairrig;

Result<std::vector<HeadFitView>> TruthLabels(const ReconstructionInput& input,
                                             const CaptureTruth& truth) {
  std::vector<HeadFitView> views;
  for (const ReconstructionView& v : input.views) {
    HR_ASSIGN_OR_RETURN(const ViewTruthMaps maps, ReadViewTruthMaps(truth.views_dir, v.id));
    views.push_back({v.camera, v.cam_from_object, maps.label});
  }
  return views;
}

// How far the true scalp (the true head mesh's vertices on its scalp) lies
// from the fitted ellipsoid's surface: where the roots go wrong.
void PrintScalpDistance(const char* what, const HeadSpec& h, const HeadSpec& truth) {
  auto model = HeadModel::Build(truth);
  if (!model.ok()) return;
  std::vector<double> distances;
  for (const Eigen::Vector3d& v : (*model)->mesh().vertices_mm) {
    if (!(*model)->OnScalp(v)) continue;
    distances.push_back(std::abs(EllipsoidRadialDistance(h, v)));
  }
  if (distances.empty()) return;
  std::sort(distances.begin(), distances.end());
  const auto share_within = [&](double mm) {
    return static_cast<double>(std::upper_bound(distances.begin(), distances.end(), mm) -
                               distances.begin()) /
           static_cast<double>(distances.size());
  };
  std::printf(
      "true scalp (%zu mesh vertices) to %s: median %.1f mm, p90 %.1f "
      "mm; within 3 mm %.2f, within 6 mm %.2f\n",
      distances.size(), what, distances[distances.size() / 2], distances[distances.size() * 9 / 10],
      share_within(3), share_within(6));
}

void PrintErrors(const HeadFitSummary& fit, const HeadSpec& truth) {
  const HeadSpec& h = fit.head;
  const Eigen::Vector3d dc = h.center_turntable_mm - truth.center_turntable_mm;
  const Eigen::Vector3d dr = h.radii_mm - truth.radii_mm;
  std::printf(
      "against the true head's ellipsoid: centre off by (%.1f, %.1f, %.1f) mm = %.1f mm, "
      "radii off by (%.1f, %.1f, %.1f) mm\n",
      dc.x(), dc.y(), dc.z(), dc.norm(), dr.x(), dr.y(), dr.z());
  std::printf(
      "face direction off by %.1f deg\n",
      RadToDeg(std::acos(std::clamp(h.scalp.face_dir.dot(truth.scalp.face_dir), -1.0, 1.0))));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s CAPTURE [--labels reconstruction|truth] [--hair-weight W] "
                 "[--prior-samples N] [--skin-scale MM]\n",
                 argv[0]);
    return 2;
  }
  const std::string capture = argv[1];
  bool truth_labels = false;
  HeadFitOptions options;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--labels") == 0)
      truth_labels = std::strcmp(argv[i + 1], "truth") == 0;
    if (std::strcmp(argv[i], "--hair-weight") == 0) options.hair_weight = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--prior-samples") == 0)
      options.prior_samples = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--skin-scale") == 0) options.skin_scale_mm = std::atof(argv[i + 1]);
  }
  auto input = LoadCaptureReconstructionInput(capture);
  auto truth = ReadCaptureTruth(capture);
  if (!input.ok() || !truth.ok() || !truth->head) {
    std::fprintf(stderr, "%s\n",
                 !input.ok()   ? input.status().ToString().c_str()
                 : !truth.ok() ? truth.status().ToString().c_str()
                               : "the ground truth records no head");
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  Result<HeadFitSummary> fit = Internal("not run");
  if (truth_labels) {
    auto views = TruthLabels(*input, *truth);
    fit = views.ok() ? FitHeadToViews(*views, options) : Result<HeadFitSummary>(views.status());
  } else {
    fit = FitHeadToReconstruction(input->views, capture + "/reconstruction", options);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!fit.ok()) {
    std::fprintf(stderr, "%s\n", fit.status().ToString().c_str());
    return 1;
  }
  std::printf("labels: %s\n%s", truth_labels ? "the ground truth's" : "the segmentation's",
              fit->BriefReport().c_str());
  PrintErrors(*fit, *truth->head);
  PrintScalpDistance("the fitted ellipsoid", fit->head, *truth->head);
  PrintScalpDistance("the rig config's skull ellipsoid", *truth->head, *truth->head);
  std::printf("time %.1f s (2 threads)\n", seconds);
  return 0;
}
