// Reconstruction II: the full hair model as strands from the oriented points
// (points.ply, point_reconstruction.h) and the head:
//   points -> strand segments (Luo 2013 Sec. 5.1, strand_segments.h), then by
//     bao-qi: root-to-tip directions per segment (Luo Sec. 6.2's MRF,
//             strand_direction.h), then strands from roots on the scalp in the
//             hybrid orientation field (Bao & Qi 2017 Sec. IV, hybrid_field.h,
//             strand_growth.h);
//     luo:    Luo's structure analysis on the undirected segments: ribbons
//             (Sec. 5.2), links between them (Sec. 6.1) and their directions
//             (Sec. 6.2; ribbons.h), wisps connected up and attached to the
//             scalp, interior wisps (Sec. 6.3, 7.1, 7.2; wisps.h), strands
//             synthesised in the wisps (Sec. 7.3);
//     naive:  strands from roots on the scalp along the points' orientation,
//             no structure analysis (the baseline each step's gain is
//             measured against).
// Everything in mm in the points' frame (the turntable frame for a capture of
// this rig); the head must be given in that frame.
//
// Outputs in <reconstruction_dir>/strands/:
//   strands.ply, strands.hair, strands.data   the hair model (core/strand_io.h)
//   segments.ply                              the segments (bao-qi: directed root to tip; luo:
//                                             undirected; none for naive)
//   ribbons.ply, wisps.ply                    luo only: every isocurve of the directed ribbons
//                                             and of the wisps as a polyline (root to tip)
//   preview.jpg                               segments, wisps (luo: centre isocurves) and
//                                             strands from four sides
//   summary.json                              options, counts, timings
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/head_spec.h"
#include "core/status.h"
#include "reconstruction/hybrid_field.h"
#include "reconstruction/ribbons.h"
#include "reconstruction/strand_direction.h"
#include "reconstruction/strand_growth.h"
#include "reconstruction/strand_merging.h"
#include "reconstruction/strand_segments.h"
#include "reconstruction/wisps.h"

namespace hairrig {

enum class StrandMethod { kBaoQi, kNaive, kLuo };
const char* StrandMethodName(StrandMethod method);  // "bao-qi", "naive", "luo"
// InvalidArgument listing the choices.
Result<StrandMethod> ParseStrandMethod(const std::string& name);

struct StrandReconstructionOptions {
  StrandMethod method = StrandMethod::kBaoQi;
  // Roots on the scalp (luo: strands synthesised). Recall rises with the
  // count at the same precision: on tight curls 40,000 roots reach a fifth
  // more of the true strands than 20,000 (docs/accuracy.md, "How many
  // strands"); the strand files and a simulation's frames grow with it.
  int strands = 40000;
  uint64_t seed = 1;  // root sampling (luo: synthesis)
  // Angle (deg, in (0, 90]) above the scalp at which roots leave it where the
  // scalp is vertical, tilted towards direction.down (bao-qi, naive;
  // RootDirection in strand_growth.h). 90 is Bao & Qi's scalp normal.
  double root_elevation_deg = 45;
  SegmentGrowthOptions segments;
  DirectionOptions direction;  // bao-qi
  HybridFieldOptions field;    // bao-qi
  StrandGrowthOptions growth;  // bao-qi, naive
  // bao-qi: a curl known beforehand (curly()) in place of the one estimated
  // from the seen strands (growth.curl), everywhere in the hair.
  Curl given_curl;
  StrandMergeOptions merging;               // bao-qi
  RibbonOptions ribbons;                    // luo
  ConnectionOptions connections;            // luo
  RibbonDirectionOptions ribbon_direction;  // luo
  WispOptions wisps;                        // luo
  SynthesisOptions synthesis;               // luo
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct StrandReconstructionSummary {
  std::string method;
  std::string head_source;  // where the head came from (for the report)
  std::string output_dir;
  int64_t points = 0;
  SegmentGrowthSummary segments;
  DirectionSummary direction;
  // bao-qi: the curl the growth winds on (none with growth.helix_continuation off).
  CurlEstimate curl;
  StrandGrowthSummary growth;  // luo: the synthesised strands' count, vertices and mean length
  StrandMergeSummary merging;  // bao-qi, after growth (growth counts the strands grown)
  RibbonSummary ribbons;
  ConnectionSummary connections;
  RibbonDirectionSummary ribbon_direction;
  WispSummary wisps;
  // seconds_direction: the segments' MRF (bao-qi) or the ribbons' (luo);
  // seconds_growth: growing (bao-qi, naive) or synthesising (luo) the strands.
  double seconds_segments = 0, seconds_direction = 0, seconds_field = 0, seconds_growth = 0,
         seconds_merging = 0, seconds_total = 0;
  double seconds_ribbons = 0, seconds_connections = 0, seconds_wisps = 0;

  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Reads <reconstruction_dir>/points.ply, writes <reconstruction_dir>/strands/.
// `skin` (may be null) is the views' skin in the points' frame: bao-qi's
// strands end in front of it (StrandGrowthOptions::end_over_skin). `views`
// (may be null) are the views the points' view lists index: bao-qi's helices
// wind out of the space they see through (StrandGrowthOptions::
// helix_out_of_free_space).
// NotFound when there are no points (run the points stage first);
// InvalidArgument for bad options, a head whose mesh cannot be loaded (naming
// it), points that give no strand segment, or (luo) no wisp.
Result<StrandReconstructionSummary> ReconstructStrands(
    const std::string& reconstruction_dir, const HeadSpec& head, const std::string& head_source,
    const StrandReconstructionOptions& options, const SkinViews* skin = nullptr,
    const std::vector<ReconstructionView>* views = nullptr);

}  // namespace hairrig
