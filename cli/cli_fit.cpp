#include <CLI/CLI.hpp>

#include "cli/cli.h"
#include "simulation/fit_strand_file.h"

namespace hairrig {
namespace {

struct FitArgs {
  FitStrandFileOptions options;
  int fixed_elements = 0;
  bool paper_root = false;
};

}  // namespace

void AddFitCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "fit", "Guide strands as G1 piecewise helices (adaptive floating tangents)");
  auto args = std::make_shared<FitArgs>();
  FitOptions& fit = args->options.fit;
  cmd->add_option("STRANDS", args->options.strands_file, "strand file (.hair, .data, .ply)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->options.out_file, "model file to write (JSON)")->required();
  cmd->add_option("--guides", fit.guides.num_guides,
                  "number of guides K (default: as many as --target-rms needs)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--target-rms", fit.guides.target_rms_mm,
                  "RMS distance (mm) of strands to their guide, when K is not given")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--fixed-n", args->fixed_elements,
                  "fixed element count per guide (the paper's N=15 baseline)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--target-error", fit.fitting.target_mean_error_mm,
                  "grow N past Algorithm 2 until the mean fit error is below this (mm); 0: "
                  "Algorithm 2 alone (paper)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--threads", fit.threads, "guides fitted in parallel (0: one thread per core)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--paper-root", args->paper_root,
                "relax the root too (Eq. 5 as printed) instead of anchoring it");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    FitOptions& options = args->options.fit;
    if (args->fixed_elements > 0) {
      options.fitting.adaptive = false;
      options.fitting.fixed_elements = args->fixed_elements;
    }
    options.fitting.anchor_root = !args->paper_root;
    DispatchSummary(dispatch, [args] { return FitStrandFile(args->options); });
  });
}

}  // namespace hairrig
