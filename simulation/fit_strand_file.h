// `hairrig fit`: a strand file (core/strand_io.h) to a fitted helix model file
// (simulation/helix_model.h), the model recording the strand file as its source.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/status.h"
#include "simulation/helix_model.h"

namespace hairrig {

struct FitStrandFileOptions {
  std::string strands_file;  // .hair, .data or .ply
  std::string out_file;      // the model (JSON); its folder is created
  FitOptions fit;

  // InvalidArgument naming the field: a missing file name, a negative guide
  // count, threads or target RMS, fitting options that FloatingTangentsOptions
  // refuses.
  Status Check() const;
};

struct FitStrandFileSummary {
  std::string out_file;
  FitSummary fit;

  // out and every FitSummary field.
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Errors: the strand file's (named), more guides asked for than it has
// strands, a strand that cannot be fitted (named with the file), the model's
// folder or file that cannot be written.
Result<FitStrandFileSummary> FitStrandFile(const FitStrandFileOptions& options);

}  // namespace hairrig
