// Reconstruction II: the full hair model as strands from the oriented points
// (points.ply, point_reconstruction.h) and the head:
//   points -> strand segments (Luo 2013 Sec. 5.1, strand_segments.h)
//          -> root-to-tip directions (Luo Sec. 6.2's MRF, strand_direction.h)
//          -> strands from roots on the scalp, by
//               bao-qi: the hybrid orientation field (Bao & Qi 2017 Sec. IV,
//                       hybrid_field.h, strand_growth.h), or
//               naive:  along the points' orientation, no structure analysis
//                       (the baseline each step's gain is measured against).
// Everything in mm in the points' frame (the turntable frame for a capture of
// this rig); the head must be given in that frame.
//
// Outputs in <reconstruction_dir>/strands/:
//   strands.ply, strands.hair, strands.data   the hair model (core/strand_io.h)
//   segments.ply                              the directed segments (root to tip; none for naive)
//   preview.jpg                               segments and strands from four sides
//   summary.json                              options, counts, timings
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "core/head_spec.h"
#include "core/status.h"
#include "reconstruction/hybrid_field.h"
#include "reconstruction/strand_direction.h"
#include "reconstruction/strand_growth.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

enum class StrandMethod { kBaoQi, kNaive };
const char* StrandMethodName(StrandMethod method);  // "bao-qi", "naive"
// InvalidArgument listing the choices.
Result<StrandMethod> ParseStrandMethod(const std::string& name);

struct StrandReconstructionOptions {
  StrandMethod method = StrandMethod::kBaoQi;
  int strands = 20000;  // roots on the scalp
  uint64_t seed = 1;    // root sampling
  SegmentGrowthOptions segments;
  DirectionOptions direction;
  HybridFieldOptions field;
  StrandGrowthOptions growth;
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct StrandReconstructionSummary {
  std::string method;
  std::string head_source;   // where the head came from (for the report)
  std::string output_dir;
  int64_t points = 0;
  SegmentGrowthSummary segments;
  DirectionSummary direction;
  StrandGrowthSummary growth;
  double seconds_segments = 0, seconds_direction = 0, seconds_field = 0, seconds_growth = 0, seconds_total = 0;

  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Reads <reconstruction_dir>/points.ply, writes <reconstruction_dir>/strands/.
// NotFound when there are no points (run the points stage first);
// InvalidArgument for bad options, a head whose mesh cannot be loaded (naming
// it) or points that give no strand segment.
Result<StrandReconstructionSummary> ReconstructStrands(const std::string& reconstruction_dir, const HeadSpec& head,
                                                       const std::string& head_source,
                                                       const StrandReconstructionOptions& options);

}  // namespace hairrig
