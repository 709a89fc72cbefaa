// A fitted hair model: the guide strands as piecewise helices (the output of
// `hairrig fit`, the input of the dynamics), stored as JSON:
//   {"format": "hairrig-helix-model", "version": 1, "source": ..., "options": {...},
//    "guides": [{"strand": i, "elements": [{"start_mm": [x,y,z], "start_tangent": [..],
//                "darboux_per_mm": [..], "length_mm": L}, ...]}, ...],
//    "cluster_of_strand": [...], "summary": {...}}
// Millimetres; the Darboux vector in radians per millimetre.
#pragma once

#include <string>
#include <vector>

#include "core/status.h"
#include "core/strands.h"
#include "simulation/floating_tangents.h"
#include "simulation/guides.h"

namespace hairrig {

struct FitOptions {
  GuideOptions guides;
  FloatingTangentsOptions fitting;
  int threads = 0;  // guides fitted in parallel; 0: one thread per core

  // InvalidArgument naming the field (guides.* and fitting.* for the nested
  // ones) for a value out of range.
  Status Check() const;
};

struct FitSummary {
  int strands = 0;
  int guides = 0;
  double guide_rms_mm = 0;   // strands to their guides
  double mean_elements = 0;  // per guide
  double mean_error_mm = 0;  // helical curve to its guide strand, mean over guides
  double max_error_mm = 0;
  double max_g1_defect_deg = 0;
  double max_cohelical_residual = 0;
  double max_relaxation_elements =
      0;  // the relaxation's largest move of a break point, in elements
  double wall_s = 0;
};

struct HelixModel {
  std::string source;              // strand file it came from
  std::vector<int> guide_strands;  // strand index of each guide
  std::vector<PiecewiseHelix> guides;
  std::vector<int> cluster_of_strand;
};

// Guides, then floating tangents on each guide. Errors name the strand.
Result<HelixModel> FitHairModel(const StrandSet& strands, const FitOptions& options,
                                FitSummary* summary);

Status WriteHelixModel(const std::string& path, const HelixModel& model, const FitSummary& summary);
// CorruptData names the file and field; a model of another format version is refused.
Result<HelixModel> ReadHelixModel(const std::string& path);

}  // namespace hairrig
