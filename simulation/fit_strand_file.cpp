#include "simulation/fit_strand_file.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/strand_io.h"
#include "core/string_format.h"

namespace hairrig {

Status FitStrandFileOptions::Check() const {
  if (strands_file.empty()) return InvalidArgument("fit: strands_file is required");
  if (out_file.empty()) return InvalidArgument("fit: out_file (--out, the model file) is required");
  if (fit.guides.num_guides < 0) {
    return InvalidArgument(
        "fit: guides.num_guides (--guides) must be 0 (as many as the target RMS needs) or more, "
        "got " +
        std::to_string(fit.guides.num_guides));
  }
  if (!(fit.guides.target_rms_mm > 0)) {
    return InvalidArgument(
        "fit: guides.target_rms_mm (--target-rms) must be a positive distance in mm");
  }
  if (fit.threads < 0) return InvalidArgument("fit: threads must be 0 (one per core) or more");
  return fit.Check().WithContext("fit");
}

nlohmann::json FitStrandFileSummary::ToJson() const {
  return {{"out", out_file},
          {"strands", fit.strands},
          {"guides", fit.guides},
          {"guide_rms_mm", fit.guide_rms_mm},
          {"mean_elements", fit.mean_elements},
          {"mean_error_mm", fit.mean_error_mm},
          {"max_error_mm", fit.max_error_mm},
          {"max_g1_defect_deg", fit.max_g1_defect_deg},
          {"max_cohelical_residual", fit.max_cohelical_residual},
          {"max_relaxation_elements", fit.max_relaxation_elements},
          {"wall_s", fit.wall_s}};
}

std::string FitStrandFileSummary::BriefReport() const {
  return StringPrintf("%s: %d guides for %d strands (RMS distance to guide %.2f mm)\n",
                      out_file.c_str(), fit.guides, fit.strands, fit.guide_rms_mm) +
         StringPrintf(
             "  %.1f helical elements per guide; fit error mean %.3f mm, max %.3f mm; G1 defect "
             "%.1e deg; %.2f s\n",
             fit.mean_elements, fit.mean_error_mm, fit.max_error_mm, fit.max_g1_defect_deg,
             fit.wall_s);
}

Result<FitStrandFileSummary> FitStrandFile(const FitStrandFileOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const StrandSet strands, ReadStrands(options.strands_file));
  if (options.fit.guides.num_guides > static_cast<int>(strands.num_strands())) {
    return InvalidArgument("--guides " + std::to_string(options.fit.guides.num_guides) +
                           " is more than the " + std::to_string(strands.num_strands()) +
                           " strands of " + options.strands_file);
  }
  const std::filesystem::path parent = std::filesystem::path(options.out_file).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  if (ec)
    return IoError(parent.string() + ": cannot create the folder for --out (" + ec.message() + ")");
  FitStrandFileSummary summary;
  summary.out_file = options.out_file;
  Result<HelixModel> fitted = FitHairModel(strands, options.fit, &summary.fit);
  if (!fitted.ok()) return fitted.status().WithContext(options.strands_file);
  HelixModel model = std::move(fitted).value();
  model.source = options.strands_file;
  HR_RETURN_IF_ERROR(WriteHelixModel(options.out_file, model, summary.fit));
  return summary;
}

}  // namespace hairrig
