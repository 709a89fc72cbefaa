// `hairrig reconstruct DIR`: oriented points from a calibrated capture, or from
// a COLMAP text model (reconstruction/point_reconstruction.h), then strands
// rooted on the subject's scalp (reconstruction/strand_reconstruction.h).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>

#include "cli/cli.h"
#include "core/log.h"
#include "reconstruction/curl_field.h"
#include "reconstruction/hair_segmentation.h"
#include "rig/reconstruct_capture.h"
#include "rig/reconstruction_input.h"

namespace hairrig {
namespace {

struct ReconstructArgs {
  std::string dir;
  std::string stage = "all";
  std::string method = "bao-qi";
  std::string head;
  int strands = StrandReconstructionOptions{}.strands;
  double root_elevation_deg = StrandReconstructionOptions{}.root_elevation_deg;
  double max_off_hair_mm = StrandGrowthOptions{}.max_off_hair_mm;
  std::string end_over_skin = StrandGrowthOptions{}.end_over_skin ? "yes" : "no";
  std::string trim_tips_over_skin = StrandGrowthOptions{}.trim_tip_over_skin ? "yes" : "no";
  std::string helix_continuation = StrandGrowthOptions{}.helix_continuation ? "yes" : "no";
  std::string cover_segments = SegmentCoverOptions{}.enabled ? "yes" : "no";
  std::string curls = CurlFieldOptions{}.enabled ? "yes" : "no";
  std::string curl_region = CurlRegionName(CurlFieldOptions{}.region);
  std::string curls_out_of_free_space =
      StrandGrowthOptions{}.helix_out_of_free_space ? "yes" : "no";
  std::string seen_tips = SeenTipOptions{}.enabled ? "yes" : "no";
  std::string colmap, images, masks;
  std::vector<int> views;
  int threads = 2;
  std::string cost = "both";
  int stride = LineMvsOptions{}.stride_px;
  int iterations = LineMvsOptions{}.iterations;
  int orientation_scales = OrientationOptions{}.scales;
  double orientation_smoothing_px = OrientationOptions{}.smoothing_px;
  double hull_tolerance = VisualHullOptions{}.max_empty_share;
  std::string shadowed_skin =
      SegmentationOptions{}.opaque_shadow_touching_skin_only ? "touching" : "all";
};

// One line per stage on a terminal (rewritten in place), with the stage's ETA.
ReconstructionProgress ProgressPrinter() {
  struct State {
    std::mutex mutex;
    std::string stage;
    std::chrono::steady_clock::time_point start;
  };
  auto state = std::make_shared<State>();
  const bool terminal = ::isatty(STDERR_FILENO) != 0;
  return [state, terminal](const std::string& stage, int done, int total) {
    std::lock_guard<std::mutex> lock(state->mutex);
    const auto now = std::chrono::steady_clock::now();
    if (stage != state->stage) {
      if (terminal && !state->stage.empty()) std::fputc('\n', stderr);
      state->stage = stage;
      state->start = now;
    }
    const double elapsed = std::chrono::duration<double>(now - state->start).count();
    const double eta = done > 0 ? elapsed * (total - done) / done : 0;
    char line[160];
    std::snprintf(line, sizeof line, "reconstruct: %s %d of %d | %.0f s | ETA %.0f s",
                  stage.c_str(), done, total, elapsed, eta);
    if (terminal) {
      std::fprintf(stderr, "\r\033[K%s", line);
      if (done == total && stage == "writing") std::fputc('\n', stderr);
      std::fflush(stderr);
    } else if (done == total) {
      LogInfo(line);
    }
  };
}

Result<ReconstructCaptureSummary> RunReconstruct(const ReconstructArgs& a) {
  ReconstructCaptureOptions options;
  options.dir = a.dir;
  HR_ASSIGN_OR_RETURN(options.stage, ParseReconstructStage(a.stage));
  options.colmap_dir = a.colmap;
  options.images_dir = a.images;
  options.masks_dir = a.masks;
  options.views = a.views;
  options.head_file = a.head;
  options.points.threads = a.threads;
  options.points.mvs.stride_px = a.stride;
  options.points.mvs.iterations = a.iterations;
  options.points.orientation.scales = a.orientation_scales;
  options.points.orientation.smoothing_px = a.orientation_smoothing_px;
  options.points.hull.max_empty_share = a.hull_tolerance;
  options.points.segmentation.opaque_shadow_touching_skin_only = a.shadowed_skin == "touching";
  options.points.mvs.cost = a.cost == "orientation"   ? MvsCost::kOrientation
                            : a.cost == "photometric" ? MvsCost::kPhotometric
                                                      : MvsCost::kBoth;
  HR_ASSIGN_OR_RETURN(options.strands.method, ParseStrandMethod(a.method));
  options.strands.strands = a.strands;
  options.strands.root_elevation_deg = a.root_elevation_deg;
  options.strands.growth.max_off_hair_mm = a.max_off_hair_mm;
  options.strands.growth.end_over_skin = a.end_over_skin == "yes";
  options.strands.growth.trim_tip_over_skin = a.trim_tips_over_skin == "yes";
  options.strands.growth.helix_continuation = a.helix_continuation == "yes";
  options.strands.growth.cover.enabled = a.cover_segments == "yes";
  options.strands.growth.curl.enabled = a.curls == "yes";
  ParseCurlRegion(a.curl_region, &options.strands.growth.curl.region);  // checked by the parser
  options.strands.growth.helix_out_of_free_space = a.curls_out_of_free_space == "yes";
  options.strands.growth.seen_tips.enabled = a.seen_tips == "yes";
  options.strands.threads = a.threads;
  options.progress = ProgressPrinter();
  return ReconstructCapture(options);
}

}  // namespace

void AddReconstructCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto args = std::make_shared<ReconstructArgs>();
  CLI::App* cmd = app.add_subcommand("reconstruct",
                                     "oriented 3D hair points, then strands rooted on the scalp, "
                                     "from a calibrated capture (or a COLMAP model) "
                                     "into DIR/reconstruction/");
  cmd->add_option("DIR", args->dir,
                  "a calibrated capture folder (with --colmap: where reconstruction/ is written)")
      ->required();
  cmd->add_option("--stage", args->stage, "points, strands (from the points already there), or all")
      ->check(CLI::IsMember({"points", "strands", "all"}))
      ->capture_default_str();
  cmd->add_option("--method", args->method,
                  "strands: bao-qi (hybrid orientation field), luo (ribbons and wisps, Luo et al. "
                  "2013) or naive "
                  "(the baseline)")
      ->check(CLI::IsMember({"bao-qi", "luo", "naive"}))
      ->capture_default_str();
  cmd->add_option("--head", args->head,
                  "the subject's head: a YAML file with a head: map, or 'fit' for an ellipsoid "
                  "fitted to the views' skin (default: the rig config's head, fitted where it has "
                  "none)")
      ->check(CLI::ExistingFile | CLI::IsMember(std::vector<std::string>{kFittedHead}));
  cmd->add_option("--strands", args->strands, "how many strands to grow (roots on the scalp)")
      ->check(CLI::Range(1, 2000000))
      ->capture_default_str();
  cmd->add_option("--root-elevation", args->root_elevation_deg,
                  "bao-qi, naive: the angle (deg) above the scalp at which strands leave it where "
                  "the scalp is vertical, rising to the normal at the crown (90: the normal "
                  "everywhere, as Bao and Qi)")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--max-off-hair", args->max_off_hair_mm,
                  "bao-qi: stop a strand once it has run this far (mm) off the seen hair, for "
                  "short hair (0: off, as Bao and Qi)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  cmd->add_option("--end-over-skin", args->end_over_skin,
                  "bao-qi: end a strand where it runs in front of skin the views see (yes), or "
                  "grow it on as Bao and Qi (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--trim-tips-over-skin", args->trim_tips_over_skin,
                  "bao-qi: trim each strand's tip back while 2 views see skin behind it (yes), "
                  "or keep the tips as grown (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--helix-continuation", args->helix_continuation,
                  "bao-qi: past the seen strands, carry a curly strand's curl on as a helix about "
                  "the field (yes), or grow it along the field alone as Bao and Qi (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--curls", args->curls,
                  "bao-qi: estimate the curl from the seen strands and, where the hair is seen to "
                  "curl, wind strands past the seen strands on that helix (yes), or not (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--curl-region", args->curl_region,
                  "bao-qi: where curly strands wind: wherever they grow (whole-hair), or only "
                  "next to the seen strands that show the curl (near-arcs: for a head whose hair "
                  "curls only in part)")
      ->check(CLI::IsMember(
          {CurlRegionName(CurlRegion::kWholeHair), CurlRegionName(CurlRegion::kNearArcs)}))
      ->capture_default_str();
  cmd->add_option("--curls-out-of-free-space", args->curls_out_of_free_space,
                  "bao-qi: a strand winding on the curl's helix keeps out of the space the "
                  "cameras see through, in front of the points they saw (yes), or winds where "
                  "its helix takes it (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--cover-segments", args->cover_segments,
                  "bao-qi: give the seen strands no strand from the roots passes along a strand "
                  "of their own, traced back to the scalp (yes), or grow from the roots alone as "
                  "Bao and Qi (no)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--seen-tips", args->seen_tips,
                  "bao-qi: a strand that follows a seen strand to a tip end no other seen strand "
                  "carries on from ends there, where the hair is not seen to curl (yes), or runs "
                  "on to the hair volume's edge as Bao and Qi (no: for hair cut to one line, "
                  "whose upper layers reach as low as the outer one)")
      ->check(CLI::IsMember({"yes", "no"}))
      ->capture_default_str();
  cmd->add_option("--colmap", args->colmap,
                  "a COLMAP text model folder (cameras.txt, images.txt) instead of a capture")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--images", args->images, "with --colmap: the folder of the model's images")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--masks", args->masks,
                  "with --colmap: hair masks, <image name>.png (non-zero = hair)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--views", args->views,
                  "only these view numbers (capture) or IMAGE_IDs (COLMAP)");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--cost", args->cost,
                  "stereo cost: both (orientation and photometric), orientation, or photometric "
                  "(the baseline)")
      ->check(CLI::IsMember({"both", "orientation", "photometric"}))
      ->capture_default_str();
  cmd->add_option("--stride", args->stride,
                  "stereo on every N-th pixel in x and y (1 = every pixel)")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->add_option("--iterations", args->iterations, "stereo PatchMatch iterations")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  cmd->add_option("--orientation-scales", args->orientation_scales,
                  "2D orientation maps: image pyramid levels the filter bank runs on, each pixel "
                  "keeping its most confident (1 = the image alone, as Luo et al. 2013)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  cmd->add_option("--orientation-smoothing", args->orientation_smoothing_px,
                  "2D orientation maps: sigma (px) of the confidence-weighted average of the "
                  "directions after the bank (0 = none, as Luo et al. 2013)")
      ->check(CLI::Range(0.0, 20.0))
      ->capture_default_str();
  cmd->add_option("--hull-tolerance", args->hull_tolerance,
                  "visual hull: the share of the views that may see the backdrop where a voxel "
                  "still stays, for a segmentation that misses thin wisps (0 = every view carves)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  cmd->add_option("--shadowed-skin", args->shadowed_skin,
                  "segmentation: the hair's region's pixels too dark to be hair blended with "
                  "the backdrop are skin in shadow everywhere (all), or only where they touch "
                  "the lit skin (touching: for a backdrop the shadowed hair hides by its colour, "
                  "as a dark blue one behind blond hair)")
      ->check(CLI::IsMember({"all", "touching"}))
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    DispatchSummary(dispatch, [args] { return RunReconstruct(*args); });
    dispatch.exit_code = FailedVerdictExitCode;
  });
}

}  // namespace hairrig
