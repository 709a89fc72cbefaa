// Reconstruction I on a calibrated capture of the simulated rig, per stereo
// cost side by side: each step's time and the accuracy against the ground
// truth. Run from the repository root:
//   build/bench/hairrig_reconstruction_bench CAPTURE [--costs both,photometric]
//       [--stride N] [--iterations N] [--mls SIGMA_MM] [--views 0,1,2,...]
//       [--neighbours N] [--views-in-cost N] [--samples N] [--follow-orientation yes|no]
//       [--prior-front MM]
//       [--prior-behind MM] [--hull-tolerance SHARE] [--hull-uncertain-alpha A] [--min-confidence
//       C] [--min-agreeing N]
//       [--multiview-direction yes|no]
//       [--direction-sigma MM] [--orientation-scales S] [--orientation-smoothing PX]
//       [--max-cost C] [--orientation-truncation DEG] [--agreement-radius CELLS] [--tag SUFFIX]
// CAPTURE is a folder from `hairrig capture --out CAPTURE --calibrate`; the
// reconstructions go to CAPTURE/bench-reconstruction-<cost>[-mls]<SUFFIX>/
// (the capture's own reconstruction/ is left alone). The last line compares
// the costs as ratios measured in this one run.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_args.h"
#include "reconstruction/point_reconstruction.h"
#include "reconstruction/reconstruction_evaluation.h"
#include "rig/reconstruction_input.h"

namespace {

using namespace hairrig;

struct Row {
  std::string cost;
  PointReconstructionSummary summary;
  ReconstructionEvaluation evaluation;
};

MvsCost ParseCost(const std::string& name) {
  return name == "orientation"   ? MvsCost::kOrientation
         : name == "photometric" ? MvsCost::kPhotometric
                                 : MvsCost::kBoth;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s CAPTURE [--costs both,photometric] [--stride N] [--iterations N] "
                 "[--mls SIGMA_MM] [--views 0,1,...] [--neighbours N] [--views-in-cost N] "
                 "[--samples N] [--prior-front MM] [--prior-behind MM] [--hull-tolerance SHARE] "
                 "[--hull-uncertain-alpha A] "
                 "[--min-confidence C] "
                 "[--min-agreeing N] "
                 "[--multiview-direction yes|no] [--direction-sigma MM] [--orientation-scales S] "
                 "[--orientation-smoothing PX] [--max-cost C] [--orientation-truncation DEG] "
                 "[--agreement-radius CELLS] [--tag SUFFIX]\n",
                 argv[0]);
    return 2;
  }
  const std::string capture = argv[1];
  std::vector<std::string> costs = {"both", "photometric"};
  PointReconstructionOptions options;
  std::vector<int> views;
  std::string tag;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--costs") == 0) {
      costs.clear();
      std::stringstream list(argv[i + 1]);
      for (std::string c; std::getline(list, c, ',');) costs.push_back(c);
    } else if (std::strcmp(argv[i], "--stride") == 0) {
      options.mvs.stride_px = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--mls") == 0) {
      options.fusion.mls_sigma_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--iterations") == 0) {
      options.mvs.iterations = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--neighbours") == 0) {
      options.mvs.neighbours = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--views-in-cost") == 0) {
      options.mvs.views_in_cost = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--samples") == 0) {
      options.mvs.samples = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--follow-orientation") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.mvs.follow_orientation)) return 2;
    } else if (std::strcmp(argv[i], "--multiview-direction") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.fusion.multiview_direction)) return 2;
    } else if (std::strcmp(argv[i], "--min-agreeing") == 0) {
      options.fusion.min_agreeing_views = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--direction-sigma") == 0) {
      options.fusion.direction_sigma_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--hull-uncertain-alpha") == 0) {
      options.hull_uncertain_alpha = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--agreement-radius") == 0) {
      options.fusion.agreement_radius_cells = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--hull-tolerance") == 0) {
      options.hull.max_empty_share = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--prior-front") == 0) {
      options.mvs.prior_front_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--prior-behind") == 0) {
      options.mvs.prior_behind_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--orientation-scales") == 0) {
      options.orientation.scales = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--orientation-smoothing") == 0) {
      options.orientation.smoothing_px = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--max-cost") == 0) {
      options.fusion.max_cost = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--orientation-truncation") == 0) {
      options.mvs.orientation_truncation_deg = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--min-confidence") == 0) {
      options.min_orientation_confidence = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--views") == 0) {
      std::stringstream list(argv[i + 1]);
      for (std::string id; std::getline(list, id, ',');) views.push_back(std::atoi(id.c_str()));
    } else if (std::strcmp(argv[i], "--tag") == 0) {
      tag = argv[i + 1];
    } else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  auto input = LoadCaptureReconstructionInput(capture);
  if (!input.ok()) {
    std::fprintf(stderr, "%s\n", input.status().ToString().c_str());
    return 1;
  }
  if (const Status selected = SelectViews(views, &*input); !selected.ok()) {
    std::fprintf(stderr, "%s\n", selected.ToString().c_str());
    return 2;
  }
  std::vector<Row> rows;
  for (const std::string& cost : costs) {
    options.mvs.cost = ParseCost(cost);
    const std::string out = capture + "/bench-reconstruction-" + cost +
                            (options.fusion.mls_sigma_mm > 0 ? "-mls" : "") + tag;
    auto summary = ReconstructPoints(*input, out, options);
    if (!summary.ok()) {
      std::fprintf(stderr, "%s: %s\n", cost.c_str(), summary.status().ToString().c_str());
      return 1;
    }
    ReconstructionEvalOptions eval;
    eval.reconstruction_dir = out;
    auto evaluation = EvaluateReconstruction(capture, eval);
    if (!evaluation.ok()) {
      std::fprintf(stderr, "%s: %s\n", cost.c_str(), evaluation.status().ToString().c_str());
      return 1;
    }
    rows.push_back({cost, *summary, *evaluation});
    std::printf("== %s\n%s%s", cost.c_str(), summary->BriefReport().c_str(),
                evaluation->BriefReport().c_str());
  }
  std::printf("\n%-12s %8s %8s %8s %8s %10s %10s %8s %8s\n", "cost", "total_s", "stereo_s",
              "depth_md", "depth_mn", "points", "P(2,20)", "R(2,20)", "F1(2,20)");
  for (const Row& r : rows) {
    const MatchScore& s = r.evaluation.visible[1];
    std::printf("%-12s %8.1f %8.1f %8.2f %8.2f %10lld %10.3f %8.3f %8.3f\n", r.cost.c_str(),
                r.summary.total_s, r.summary.stereo_s, r.evaluation.depth_median_mm,
                r.evaluation.depth_mean_mm, static_cast<long long>(r.evaluation.points),
                s.precision, s.recall, s.f1);
  }
  if (rows.size() >= 2 && rows[0].evaluation.depth_median_mm > 0) {
    std::printf("depth median error, %s / %s: %.2f\n", rows[1].cost.c_str(), rows[0].cost.c_str(),
                rows[1].evaluation.depth_median_mm / rows[0].evaluation.depth_median_mm);
  }
  return 0;
}
