#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "core/strand_io.h"
#include "rig/cli.h"
#include "simulation/helix_model.h"

namespace hairrig {
namespace {

struct FitArgs {
  std::string strands;
  std::string out;
  int guides = 0;
  double target_rms_mm = 5;
  int fixed_elements = 0;
  bool paper_root = false;
  double target_error_mm = 0.05;
};

Result<nlohmann::json> RunFit(const FitArgs& a) {
  HR_ASSIGN_OR_RETURN(StrandSet strands, ReadStrands(a.strands));
  FitOptions options;
  options.guides.num_guides = a.guides;
  options.guides.target_rms_mm = a.target_rms_mm;
  if (a.guides > static_cast<int>(strands.num_strands())) {
    return InvalidArgument("--guides " + std::to_string(a.guides) + " is more than the " +
                           std::to_string(strands.num_strands()) + " strands of " + a.strands);
  }
  if (a.fixed_elements > 0) {
    options.fitting.adaptive = false;
    options.fitting.fixed_elements = a.fixed_elements;
  }
  options.fitting.anchor_root = !a.paper_root;
  options.fitting.target_mean_error_mm = a.target_error_mm;
  const std::filesystem::path parent = std::filesystem::path(a.out).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  if (ec) return IoError(parent.string() + ": cannot create the folder for --out (" + ec.message() + ")");
  FitSummary s;
  Result<HelixModel> fitted = FitHairModel(strands, options, &s);
  if (!fitted.ok()) return fitted.status().WithContext(a.strands);
  HelixModel model = std::move(fitted).value();
  model.source = a.strands;
  HR_RETURN_IF_ERROR(WriteHelixModel(a.out, model, s));
  return nlohmann::json{{"out", a.out},
                        {"strands", s.strands},
                        {"guides", s.guides},
                        {"guide_rms_mm", s.guide_rms_mm},
                        {"mean_elements", s.mean_elements},
                        {"mean_error_mm", s.mean_error_mm},
                        {"max_error_mm", s.max_error_mm},
                        {"max_g1_defect_deg", s.max_g1_defect_deg},
                        {"max_cohelical_residual", s.max_cohelical_residual},
                        {"max_relaxation_elements", s.max_relaxation_elements},
                        {"wall_s", s.wall_s}};
}

void PrintFit(const nlohmann::json& j) {
  std::printf("%s: %d guides for %d strands (RMS distance to guide %.2f mm)\n", j["out"].get<std::string>().c_str(),
              j["guides"].get<int>(), j["strands"].get<int>(), j["guide_rms_mm"].get<double>());
  std::printf("  %.1f helical elements per guide; fit error mean %.3f mm, max %.3f mm; G1 defect %.1e deg; %.2f s\n",
              j["mean_elements"].get<double>(), j["mean_error_mm"].get<double>(), j["max_error_mm"].get<double>(),
              j["max_g1_defect_deg"].get<double>(), j["wall_s"].get<double>());
}

}  // namespace

void AddFitCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand("fit", "Guide strands as G1 piecewise helices (adaptive floating tangents)");
  auto args = std::make_shared<FitArgs>();
  cmd->add_option("STRANDS", args->strands, "strand file (.hair, .data, .ply)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "model file to write (JSON)")->required();
  cmd->add_option("--guides", args->guides, "number of guides K (default: as many as --target-rms needs)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--target-rms", args->target_rms_mm, "RMS distance (mm) of strands to their guide, when K is not given")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--fixed-n", args->fixed_elements, "fixed element count per guide (the paper's N=15 baseline)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--target-error", args->target_error_mm,
                  "grow N past Algorithm 2 until the mean fit error is below this (mm); 0: Algorithm 2 alone (paper)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--paper-root", args->paper_root, "relax the root too (Eq. 5 as printed) instead of anchoring it");
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, &dispatch] {
    dispatch.action = [args] { return RunFit(*args); };
    dispatch.print_human = PrintFit;
  });
}

}  // namespace hairrig
