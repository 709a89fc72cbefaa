#include "reconstruction/strand_reconstruction.h"

#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/clock.h"
#include "core/file_util.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/strand_io.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/strand_preview.h"

namespace hairrig {

namespace {

double SecondsSince(int64_t start_ns) { return static_cast<double>(SteadyNowNs() - start_ns) * 1e-9; }

StrandSet SegmentsAsStrands(const std::vector<StrandSegment>& segments) {
  StrandSet set;
  for (const StrandSegment& s : segments) set.AddStrand(s.points_mm);
  return set;
}

Status WriteOutputs(const std::string& dir, const StrandSet& strands, const std::vector<StrandSegment>& segments,
                    const StrandReconstructionSummary& summary) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) return IoError(dir + ": cannot create the strands folder: " + error.message());
  for (const char* name : {"strands.ply", "strands.hair", "strands.data"}) {
    HR_RETURN_IF_ERROR(WriteStrands(dir + "/" + name, strands));
  }
  const StrandSet segment_set = SegmentsAsStrands(segments);
  HR_RETURN_IF_ERROR(WriteStrands(dir + "/segments.ply", segment_set));
  const cv::Mat preview = RenderStrandPreview({&segment_set, &strands}, {"segments", "strands"}, StrandPreviewOptions{});
  HR_RETURN_IF_ERROR(WriteImageAtomic(dir + "/preview.jpg", preview));
  return WriteFileAtomic(dir + "/summary.json", summary.ToJson().dump(1));
}

}  // namespace

const char* StrandMethodName(StrandMethod method) { return method == StrandMethod::kNaive ? "naive" : "bao-qi"; }

Result<StrandMethod> ParseStrandMethod(const std::string& name) {
  if (name == "bao-qi") return StrandMethod::kBaoQi;
  if (name == "naive") return StrandMethod::kNaive;
  return InvalidArgument("strand method '" + name + "': expected bao-qi or naive");
}

Status StrandReconstructionOptions::Check() const {
  if (strands < 1 || strands > 2000000) return InvalidArgument("strands must lie in 1..2000000");
  if (threads < 1) return InvalidArgument("threads must be at least 1");
  HR_RETURN_IF_ERROR(segments.Check());
  HR_RETURN_IF_ERROR(direction.Check());
  HR_RETURN_IF_ERROR(field.Check());
  return growth.Check();
}

nlohmann::json StrandReconstructionSummary::ToJson() const {
  return {{"format", "hairrig-reconstruction-strands"},
          {"version", 1},
          {"method", method},
          {"head", head_source},
          {"points", points},
          {"segments",
           {{"count", segments.segments},
            {"seeds_grown", segments.seeds_grown},
            {"vertices", segments.vertices},
            {"mean_length_mm", segments.mean_length_mm},
            {"splits", segments.splits},
            {"stops", {{"turn", segments.stops_turn}, {"hole", segments.stops_hole}, {"mls", segments.stops_mls},
                       {"length", segments.stops_length}}}}},
          {"direction",
           {{"links", direction.links},
            {"overlaps", direction.overlaps},
            {"reversed", direction.reversed},
            {"truncated_pairs", direction.truncated_pairs},
            {"against_own_height_and_scalp", direction.unary_disagreements},
            {"energy", direction.energy}}},
          {"strands",
           {{"count", growth.strands},
            {"vertices", growth.vertices},
            {"mean_length_mm", growth.mean_length_mm},
            {"stopped_at_volume", growth.stopped_volume},
            {"stopped_at_max_length", growth.stopped_length},
            {"dropped_short", growth.dropped_short}}},
          {"seconds",
           {{"segments", seconds_segments},
            {"direction", seconds_direction},
            {"field", seconds_field},
            {"growth", seconds_growth},
            {"total", seconds_total}}},
          {"output_dir", output_dir}};
}

std::string StrandReconstructionSummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "strands (" << method << ", head: " << head_source << "): " << growth.strands << " strands, mean "
    << growth.mean_length_mm << " mm, from " << segments.segments << " segments (mean " << segments.mean_length_mm
    << " mm; " << direction.reversed << " reversed by the direction MRF) of " << points << " points\n";
  s << "  time: segments " << seconds_segments << " s, direction " << seconds_direction << " s, field "
    << seconds_field << " s, growth " << seconds_growth << " s, total " << seconds_total << " s\n";
  s << "  written: " << output_dir << "/strands.{ply,hair,data}, segments.ply, summary.json\n";
  return s.str();
}

Result<StrandReconstructionSummary> ReconstructStrands(const std::string& reconstruction_dir, const HeadSpec& head_spec,
                                                       const std::string& head_source,
                                                       const StrandReconstructionOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  const int64_t start = SteadyNowNs();
  StrandReconstructionSummary summary;
  summary.method = StrandMethodName(o.method);
  summary.head_source = head_source;
  summary.output_dir = reconstruction_dir + "/strands";
  const std::string points_file = reconstruction_dir + "/points.ply";
  if (!std::filesystem::exists(points_file)) {
    return NotFound(points_file + ": no oriented points; run `hairrig reconstruct DIR --stage points` first");
  }
  HR_ASSIGN_OR_RETURN(const std::vector<OrientedPoint> points, ReadPointCloudPly(points_file));
  summary.points = static_cast<int64_t>(points.size());
  HR_ASSIGN_OR_RETURN(const std::unique_ptr<HeadModel> head, HeadModel::Build(head_spec));

  int64_t t = SteadyNowNs();
  std::vector<StrandSegment> segments;
  if (o.method != StrandMethod::kNaive) {  // the baseline uses no structure
    segments = GrowStrandSegments(points, o.segments, &summary.segments);
    summary.seconds_segments = SecondsSince(t);
    if (segments.empty()) {
      return InvalidArgument(points_file + ": the points give no strand segment (too few or too sparse)");
    }
    t = SteadyNowNs();
    DirectionOptions direction = o.direction;
    direction.threads = o.threads;
    summary.direction = DirectSegments(&segments, head.get(), direction);
    summary.seconds_direction = SecondsSince(t);
  }

  const std::vector<DirectedRoot> roots = SampleScalpRoots(*head, o.strands, o.seed);
  StrandGrowthOptions growth = o.growth;
  growth.threads = o.threads;
  StrandSet strands;
  if (o.method == StrandMethod::kBaoQi) {
    t = SteadyNowNs();
    HR_ASSIGN_OR_RETURN(const HybridOrientationField field,
                        HybridOrientationField::Build(segments, roots, head.get(), o.field));
    summary.seconds_field = SecondsSince(t);
    t = SteadyNowNs();
    strands = GrowStrandsInField(field, roots, head.get(), growth, &summary.growth);
  } else {
    t = SteadyNowNs();
    const PointOrientationField field(points, o.segments.sigma_mm);
    strands = GrowStrandsAlongPoints(field, roots, head.get(), growth, &summary.growth);
  }
  summary.seconds_growth = SecondsSince(t);
  summary.seconds_total = SecondsSince(start);
  HR_RETURN_IF_ERROR(WriteOutputs(summary.output_dir, strands, segments, summary));
  return summary;
}

}  // namespace hairrig
