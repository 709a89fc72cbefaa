// Reconstruction II on a capture of the simulated rig whose points exist
// (`hairrig reconstruct CAPTURE --stage points`): each strand method's steps
// timed, side by side. Run from the repository root:
//   build/bench/hairrig_strand_bench CAPTURE [--methods bao-qi,luo,naive] [--strands N]
//       [--head FILE|fit] [--volume-bound B] [--root-elevation DEG] [--alpha-link W]
//       [--alpha-close W] [--share-link-ends yes|no] [--share-overlaps yes|no]
//       [--whole-head-in-volume yes|no] [--max-off-hair MM] [--off-hair MM]
//       [--merge-run MM] [--merge-distance MM] [--voxel MM] [--follow-radius MM]
//       [--end-over-skin yes|no] [--segment-curvature-weight W] [--segment-sigma MM]
//       [--segment-step MM] [--points capture|truth|true-directions]
//       [--helix-continuation yes|no] [--helix-window MM] [--helix-min-curvature K]
//       [--curl-field yes|no] [--curl-oracle RADIUS_MM,PITCH_MM[,+1|-1]] [--curl-min-depth MM]
//       [--curl-start-on-bend yes|no] [--curl-bend-axis-relax MM] [--curl-region
//       near-arcs|whole-hair] [--curl-region-cell MM]
//       [--curl-radius-from
//       helix-fit|helix-fit-less-bias|curvature-and-torsion|curvature|turn-rate]
//       [--helix-out-of-free-space yes|no] [--free-space-views N] [--free-space-margin MM]
//       [--follow-weight W] [--skin-min-share S] [--skin-min-views N]
//       [--trim-tips-over-skin yes|no] [--tip-skin-min-share S] [--tip-skin-min-views N]
//       [--scalp-skin-band MM] [--tip-skin-margin PX]
//       [--cover-segments yes|no] [--cover-min-uncovered MM] [--cover-radius MM]
//       [--cover-graft-radius MM] [--seen-tips yes|no] [--seen-tip-reach MM]
//       [--seen-tip-window AHEAD_MM,LATERAL_MM,ANGLE_DEG] [--seen-tip-carry-on MM]
//       [--seen-tip-points-ahead SHARE]
//       [--skin-labels capture|truth] [--overlap-stride K] [--max-overlaps K] [--overlap-mm MM]
//       [--out-suffix S]
//       [--score yes|no]
// --points truth grows the strands from the true visible surface instead of the
// capture's points (as many points, reconstruction_evaluation.h PointsFromTruth),
// the strand stage's ceiling; true-directions keeps the capture's points with the
// true strands' directions, what the points' directions cost.
// --curl-field no leaves the curl field out (curl_field.h; the strands past the
// seen strands then follow helix_continuation.h alone); --curl-oracle gives every
// strand the curl given (radius, pitch, handedness: the simulated wig's
// curl_radius_mm and curl_pitch_mm, right-handed, for its ceiling) in place of
// the estimate. --curl-radius-from picks what the estimate's radius and pitch
// come from (CurlRadiusFrom; helix-fit-less-bias by default).
// --helix-out-of-free-space no lets the helices wind in front of the seen hair
// (StrandGrowthOptions::helix_out_of_free_space); --free-space-views and
// --free-space-margin set its FreeSpaceOptions::min_views and margin_mm.
// --curl-region near-arcs winds the strands only near the seen arcs, in the
// cells of --curl-region-cell MM next to a seen arc's (CurlFieldOptions::region,
// region_mm 20), instead of wherever they grow (whole-hair).
// --curl-min-depth MM: strands wind only MM or further from the
// seen strands' ribbons (CurlFieldOptions::min_depth_mm; 0 by default).
// --curl-start-on-bend no starts every helix about the field's direction
// (HelixGuide::Start) instead of on the bend of the seen strand just left;
// --curl-bend-axis-relax MM is how far such a helix's axis takes to turn
// towards the field's (CurlFieldOptions::bend_axis_relax_mm, 10).
// --scalp-skin-band MM: skin seen behind a vertex above the hairline and within
// MM of the head is the scalp showing through the hair, not bare skin
// (SkinViews::ExcludeScalp; 12 as the reconstruction, 0 counts it as skin).
// --cover-segments no grows the strands from the scalp's roots alone (Bao &
// Qi), without the strands through the seen strands they leave uncovered
// (SegmentCoverOptions in strand_growth.h).
// --seen-tips no lets a strand that follows a seen strand to its tip end carry
// on (seen_tips.h; the paper's growth); --seen-tip-reach sets
// SeenTipOptions::reach_mm, --seen-tip-window its ahead_max_mm, lateral_mm and
// max_angle_deg (the window a continuing seen strand is looked for in),
// --seen-tip-carry-on MM its carry_on_mm (how far ahead of the tip the
// continuing seen strand must reach; 0: any vertex in the window continues it),
// --seen-tip-points-ahead its points_ahead_max_share (a tip is kept only where
// the oriented points ahead of it number under this share of those behind it;
// 0: the points are not asked).
// --skin-labels truth gives the growth's skin tests (end over skin, tips trimmed
// back) the simulated rig's true labels in place of the segmentation's: their
// ceiling.
// --head fit roots the strands on a head fitted to the capture's labels
// (rig/reconstruction_input.h; it writes CAPTURE/reconstruction/head.yaml).
// The strands go to CAPTURE/bench-strands-<method><S>/strands/ (the capture's own
// reconstruction is left alone, but for the head.yaml a fitted head writes), and each method's
// strands are scored by the strand protocol of `hairrig eval reconstruction` (unless --score no),
// which writes preview_truth.jpg beside them (the model above the ground truth's strands),
// then the consistency the truth's own strands score at the same count.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_args.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/strand_io.h"
#include "reconstruction/reconstruction_evaluation.h"
#include "reconstruction/skin_views.h"
#include "reconstruction/strand_evaluation.h"
#include "reconstruction/strand_reconstruction.h"
#include "rig/reconstruction_input.h"

namespace {

// The simulated rig's true label of each view (ground_truth/views/NNN_label.png,
// NNN the view's number, the first three characters of its name); an empty
// label where there is none, which leaves that view out of the skin test.
std::vector<cv::Mat1b> TrueLabels(const std::string& capture,
                                  const std::vector<hairrig::ReconstructionView>& views) {
  std::vector<cv::Mat1b> labels;
  for (const hairrig::ReconstructionView& view : views) {
    const hairrig::Result<cv::Mat> label = hairrig::ReadImageFile(
        capture + "/ground_truth/views/" + view.name.substr(0, 3) + "_label.png",
        cv::IMREAD_GRAYSCALE);
    labels.push_back(label.ok() ? cv::Mat1b(*label) : cv::Mat1b());
  }
  return labels;
}

// The --curl-radius-from value; false (with a message) for an unknown one.
bool ReadCurlRadiusFrom(const std::string& name, hairrig::CurlRadiusFrom* out) {
  if (hairrig::ParseCurlRadiusFrom(name, out)) return true;
  std::string known;
  for (const hairrig::CurlRadiusFrom from : hairrig::kCurlRadiusFroms)
    known += std::string(known.empty() ? "" : ", ") + hairrig::CurlRadiusFromName(from);
  std::fprintf(stderr, "--curl-radius-from: one of %s, not '%s'\n", known.c_str(), name.c_str());
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hairrig;
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: %s CAPTURE [--methods bao-qi,luo,naive] [--strands N] [--head FILE|fit] "
        "[--volume-bound B] [--root-elevation DEG] [--alpha-link W] [--alpha-close W] "
        "[--share-link-ends yes|no] [--share-overlaps yes|no] [--whole-head-in-volume yes|no] "
        "[--max-off-hair MM] [--off-hair MM] [--merge-run MM] [--merge-distance MM] "
        "[--voxel MM] [--follow-radius MM] [--follow-weight W] [--end-over-skin yes|no] "
        "[--skin-min-share S] [--skin-min-views N] [--trim-tips-over-skin yes|no] "
        "[--scalp-skin-band MM] [--tip-skin-margin PX] "
        "[--cover-segments yes|no] [--cover-min-uncovered MM] [--cover-radius MM] "
        "[--cover-graft-radius MM] [--seen-tips yes|no] [--seen-tip-reach MM] "
        "[--seen-tip-window AHEAD_MM,LATERAL_MM,ANGLE_DEG] [--seen-tip-carry-on MM] "
        "[--seen-tip-points-ahead SHARE] "
        "[--tip-skin-min-share S] [--tip-skin-min-views N] "
        "[--segment-curvature-weight W] [--segment-sigma MM] [--segment-step MM] "
        "[--points capture|truth|true-directions] [--skin-labels capture|truth] "
        "[--helix-continuation yes|no] [--helix-window MM] [--helix-min-curvature K] "
        "[--curl-field yes|no] [--curl-oracle RADIUS_MM,PITCH_MM[,+1|-1]] [--curl-min-depth MM] "
        "[--curl-start-on-bend yes|no] [--curl-bend-axis-relax MM] [--curl-region "
        "near-arcs|whole-hair] [--curl-region-cell MM] "
        "[--curl-radius-from "
        "helix-fit|helix-fit-less-bias|curvature-and-torsion|curvature|turn-rate] "
        "[--helix-out-of-free-space yes|no] [--free-space-views N] [--free-space-margin MM] "
        "[--overlap-stride K] "
        "[--max-overlaps K] [--overlap-mm MM] [--out-suffix "
        "S] "
        "[--score yes|no]\n",
        argv[0]);
    return 2;
  }
  const std::string capture = argv[1];
  std::vector<std::string> methods = {"bao-qi", "naive"};
  StrandReconstructionOptions options;
  std::string head_file, out_suffix;
  bool score = true;
  std::string points_from = "capture";
  std::string skin_labels = "capture";
  double scalp_band_mm = kScalpSkinBandMm;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--methods") == 0) {
      methods.clear();
      std::stringstream list(argv[i + 1]);
      for (std::string m; std::getline(list, m, ',');) methods.push_back(m);
    } else if (std::strcmp(argv[i], "--strands") == 0) {
      options.strands = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--head") == 0) {
      head_file = argv[i + 1];
    } else if (std::strcmp(argv[i], "--segment-curvature-weight") == 0) {
      options.segments.smooth_curvature = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--segment-sigma") == 0) {
      options.segments.sigma_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--segment-step") == 0) {
      options.segments.step_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--volume-bound") == 0) {
      options.growth.volume_bound = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--root-elevation") == 0) {
      options.root_elevation_deg = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--overlap-stride") == 0) {
      options.direction.overlap_stride = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--overlap-mm") == 0) {
      options.direction.overlap_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--max-overlaps") == 0) {
      options.direction.max_overlaps = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--alpha-link") == 0) {
      options.direction.alpha_link = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--alpha-close") == 0) {
      options.direction.alpha_close = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--share-overlaps") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.direction.share_overlaps)) return 2;
    } else if (std::strcmp(argv[i], "--follow-radius") == 0) {
      options.growth.follow_radius_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--cover-segments") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.cover.enabled)) return 2;
    } else if (std::strcmp(argv[i], "--seen-tips") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.seen_tips.enabled)) return 2;
    } else if (std::strcmp(argv[i], "--seen-tip-reach") == 0) {
      options.growth.seen_tips.reach_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--seen-tip-carry-on") == 0) {
      options.growth.seen_tips.carry_on_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--seen-tip-points-ahead") == 0) {
      options.growth.seen_tips.points_ahead_max_share = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--seen-tip-window") == 0) {
      SeenTipOptions& t = options.growth.seen_tips;
      if (std::sscanf(argv[i + 1], "%lf,%lf,%lf", &t.ahead_max_mm, &t.lateral_mm,
                      &t.max_angle_deg) != 3) {
        std::fprintf(stderr,
                     "--seen-tip-window: expected AHEAD_MM,LATERAL_MM,ANGLE_DEG, got '%s'\n",
                     argv[i + 1]);
        return 2;
      }
    } else if (std::strcmp(argv[i], "--cover-min-uncovered") == 0) {
      options.growth.cover.min_uncovered_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--cover-graft-radius") == 0) {
      options.growth.cover.graft_radius_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--cover-radius") == 0) {
      options.growth.cover.coverage.radius_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--follow-weight") == 0) {
      options.growth.follow_weight = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--voxel") == 0) {
      options.field.voxel_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--merge-run") == 0) {
      options.merging.run_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--merge-distance") == 0) {
      options.merging.distance_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--max-off-hair") == 0) {
      options.growth.max_off_hair_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--off-hair") == 0) {
      options.growth.off_hair_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--helix-continuation") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.helix_continuation)) return 2;
    } else if (std::strcmp(argv[i], "--curl-oracle") == 0) {
      Curl& curl = options.given_curl;
      if (std::sscanf(argv[i + 1], "%lf,%lf,%d", &curl.radius_mm, &curl.pitch_mm,
                      &curl.handedness) < 2 ||
          std::abs(curl.handedness) != 1) {
        std::fprintf(stderr, "--curl-oracle: RADIUS_MM,PITCH_MM[,+1|-1], not '%s'\n", argv[i + 1]);
        return 2;
      }
    } else if (std::strcmp(argv[i], "--curl-start-on-bend") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.curl.start_on_bend)) return 2;
    } else if (std::strcmp(argv[i], "--curl-bend-axis-relax") == 0) {
      options.growth.curl.bend_axis_relax_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--curl-region") == 0) {
      if (!ParseCurlRegion(argv[i + 1], &options.growth.curl.region)) {
        std::fprintf(stderr, "--curl-region: near-arcs or whole-hair, not '%s'\n", argv[i + 1]);
        return 2;
      }
    } else if (std::strcmp(argv[i], "--curl-region-cell") == 0) {
      options.growth.curl.region_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--curl-min-depth") == 0) {
      options.growth.curl.min_depth_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--curl-radius-from") == 0) {
      if (!ReadCurlRadiusFrom(argv[i + 1], &options.growth.curl.radius_from)) return 2;
    } else if (std::strcmp(argv[i], "--helix-out-of-free-space") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.helix_out_of_free_space)) return 2;
    } else if (std::strcmp(argv[i], "--free-space-views") == 0) {
      options.growth.free_space.min_views = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--free-space-margin") == 0) {
      options.growth.free_space.margin_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--curl-field") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.curl.enabled)) return 2;
    } else if (std::strcmp(argv[i], "--helix-window") == 0) {
      options.growth.helix.window_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--helix-min-curvature") == 0) {
      options.growth.helix.min_curvature_per_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--end-over-skin") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.end_over_skin)) return 2;
    } else if (std::strcmp(argv[i], "--scalp-skin-band") == 0) {
      scalp_band_mm = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--skin-min-share") == 0) {
      options.growth.skin.min_share = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--skin-min-views") == 0) {
      options.growth.skin.min_views = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--tip-skin-min-share") == 0) {
      options.growth.tip_skin.min_share = std::atof(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--tip-skin-margin") == 0) {
      options.growth.tip_skin_margin_px = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--tip-skin-min-views") == 0) {
      options.growth.tip_skin.min_views = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--trim-tips-over-skin") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.growth.trim_tip_over_skin)) return 2;
    } else if (std::strcmp(argv[i], "--whole-head-in-volume") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.field.whole_head_in_volume)) return 2;
    } else if (std::strcmp(argv[i], "--share-link-ends") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &options.direction.share_link_ends)) return 2;
    } else if (std::strcmp(argv[i], "--out-suffix") == 0) {
      out_suffix = argv[i + 1];
    } else if (std::strcmp(argv[i], "--score") == 0) {
      if (!ParseYesNo(argv[i], argv[i + 1], &score)) return 2;
    } else if (std::strcmp(argv[i], "--skin-labels") == 0) {
      skin_labels = argv[i + 1];
    } else if (std::strcmp(argv[i], "--points") == 0) {
      points_from = argv[i + 1];
    }
  }
  if (skin_labels != "capture" && skin_labels != "truth") {
    std::fprintf(stderr, "--skin-labels: 'capture' or 'truth', not '%s'\n", skin_labels.c_str());
    return 2;
  }
  auto input = LoadCaptureReconstructionInput(capture);
  if (!input.ok()) {
    std::fprintf(stderr, "%s\n", input.status().ToString().c_str());
    return 1;
  }
  SubjectHeadRequest request;
  request.head_file = head_file;
  request.capture_dir = capture;
  request.reconstruction_dir = capture + "/reconstruction";
  request.views = &input->views;
  auto head = ResolveSubjectHead(request);
  if (head.ok() && head->fit) std::printf("%s", head->fit->BriefReport().c_str());
  auto truth = ReadStrands(capture + "/ground_truth/ground_truth_strands.ply");
  if (!head.ok() || !truth.ok()) {
    std::fprintf(stderr, "%s\n", (!head.ok() ? head.status() : truth.status()).ToString().c_str());
    return 1;
  }
  // The views' skin from the capture's own points stage (its label masks), or
  // from the simulated rig's true labels: the skin tests' ceiling.
  Result<SkinViews> skin =
      skin_labels == "truth"
          ? SkinViews::FromLabels(input->views, TrueLabels(capture, input->views),
                                  head->spec.center_turntable_mm)
          : SkinViews::Load(input->views, capture + "/reconstruction/masks",
                            head->spec.center_turntable_mm);
  if (!skin.ok()) std::fprintf(stderr, "no skin test: %s\n", skin.status().ToString().c_str());
  auto head_model = HeadModel::Build(head->spec);
  if (!head_model.ok()) {
    std::fprintf(stderr, "%s\n", head_model.status().ToString().c_str());
    return 1;
  }
  if (skin.ok()) skin->ExcludeScalp(head_model->get(), scalp_band_mm);
  // The strand stage's input: the capture's points, or points made from the truth.
  std::optional<std::vector<OrientedPoint>> truth_points;
  if (points_from != "capture") {
    if (points_from != "truth" && points_from != "true-directions") {
      std::fprintf(stderr, "--points: 'capture', 'truth' or 'true-directions', not '%s'\n",
                   points_from.c_str());
      return 2;
    }
    auto made = PointsFromTruth(capture,
                                points_from == "truth" ? TruthPointsKind::kVisibleSurface
                                                       : TruthPointsKind::kTrueDirections,
                                ReconstructionEvalOptions{});
    if (!made.ok()) {
      std::fprintf(stderr, "%s\n", made.status().ToString().c_str());
      return 1;
    }
    std::printf("points from the truth (%s): %zu\n", points_from.c_str(), made->size());
    truth_points = std::move(made).value();
  }
  for (const std::string& name : methods) {
    auto method = ParseStrandMethod(name);
    if (!method.ok()) {
      std::fprintf(stderr, "%s\n", method.status().ToString().c_str());
      return 2;
    }
    options.method = *method;
    const std::string dir = capture + "/bench-strands-" + name + out_suffix;
    fs::create_directories(dir);
    if (truth_points) {
      const Status written = WritePointCloudPly(dir + "/points.ply", *truth_points);
      if (!written.ok()) {
        std::fprintf(stderr, "%s\n", written.ToString().c_str());
        return 1;
      }
    } else {
      fs::copy_file(capture + "/reconstruction/points.ply", dir + "/points.ply",
                    fs::copy_options::overwrite_existing);
    }
    auto summary = ReconstructStrands(dir, head->spec, head->source, options,
                                      skin.ok() ? &*skin : nullptr, &input->views);
    if (!summary.ok()) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), summary.status().ToString().c_str());
      return 1;
    }
    std::printf("%s", summary->BriefReport().c_str());
    if (!score) continue;
    ReconstructionEvalOptions eval;
    eval.strands_dir = dir;
    auto scored = EvaluateReconstruction(capture, eval);
    if (!scored.ok() || !scored->strands) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(),
                   scored.ok() ? "no strands scored" : scored.status().ToString().c_str());
      return 1;
    }
    std::printf("%s scored as `hairrig eval reconstruction` does:\n%s", name.c_str(),
                scored->strands->BriefReport().c_str());
    if (scored->strands_over_true_skin && scored->truth_over_true_skin)
      std::printf(
          "  in front of the true bare skin: %.2f %% of samples (the truth's own %.2f %%)\n",
          100 * *scored->strands_over_true_skin, 100 * *scored->truth_over_true_skin);
  }
  if (score) {
    const auto reference = ConsistencyOfTruthSubset(*truth, options.strands, StrandEvalOptions{});
    if (!reference.ok()) {
      std::fprintf(stderr, "%s\n", reference.status().ToString().c_str());
      return 1;
    }
    std::printf(
        "consistency reference: %lld of the true strands taken as the reconstruction, the other "
        "%lld score %.3f (strand_evaluation.h, ConsistencyOfTruthSubset)\n",
        static_cast<long long>(reference->kept_strands),
        static_cast<long long>(reference->scored_strands), reference->consistency);
  }
  return 0;
}
