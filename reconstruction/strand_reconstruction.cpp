#include "reconstruction/strand_reconstruction.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/clock.h"
#include "core/file_util.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/log.h"
#include "core/strand_io.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/strand_preview.h"

namespace hairrig {

namespace {

StrandSet SegmentsAsStrands(const std::vector<StrandSegment>& segments) {
  StrandSet set;
  for (const StrandSegment& s : segments) set.AddStrand(s.points_mm);
  return set;
}

// Every isocurve of every grid as a strand.
template <typename Grid>
StrandSet IsocurvesAsStrands(const std::vector<Grid>& grids) {
  StrandSet set;
  for (const Grid& grid : grids)
    for (const std::vector<Eigen::Vector3f>& isocurve : grid.isocurves) set.AddStrand(isocurve);
  return set;
}

StrandSet WispCentres(const std::vector<Wisp>& wisps) {
  StrandSet set;
  for (const Wisp& wisp : wisps) set.AddStrand(wisp.center());
  return set;
}

// What a method gives the outputs; ribbons and wisps are luo's.
struct StrandModel {
  StrandSet strands, segments, ribbons, wisps, wisp_centres;
  bool structure = false;  // ribbons and wisps are written
};

Status WriteOutputs(const std::string& dir, const StrandModel& model,
                    const StrandReconstructionSummary& summary) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) return IoError(dir + ": cannot create the strands folder: " + error.message());
  for (const char* name : {"strands.ply", "strands.hair", "strands.data"}) {
    HR_RETURN_IF_ERROR(WriteStrands(dir + "/" + name, model.strands));
  }
  HR_RETURN_IF_ERROR(WriteStrands(dir + "/segments.ply", model.segments));
  std::vector<const StrandSet*> rows = {&model.segments, &model.strands};
  std::vector<std::string> labels = {"segments", "strands"};
  if (model.structure) {
    HR_RETURN_IF_ERROR(WriteStrands(dir + "/ribbons.ply", model.ribbons));
    HR_RETURN_IF_ERROR(WriteStrands(dir + "/wisps.ply", model.wisps));
    rows.insert(rows.begin() + 1, &model.wisp_centres);
    labels.insert(labels.begin() + 1, "wisps");
  }
  HR_ASSIGN_OR_RETURN(const cv::Mat preview,
                      RenderStrandPreview(rows, labels, StrandPreviewOptions{}));
  HR_RETURN_IF_ERROR(WriteImageAtomic(dir + "/preview.jpg", preview));
  return WriteFileAtomic(dir + "/summary.json", summary.ToJson().dump(1));
}

void SummariseStrands(const StrandSet& strands, StrandGrowthSummary* summary) {
  summary->strands = static_cast<int64_t>(strands.num_strands());
  summary->vertices = static_cast<int64_t>(strands.num_points());
  const std::vector<double> lengths = strands.StrandLengths();
  double total = 0;
  for (double length : lengths) total += length;
  summary->mean_length_mm = lengths.empty() ? 0 : total / static_cast<double>(lengths.size());
}

Result<std::vector<StrandSegment>> GrowSegments(const std::vector<OrientedPoint>& points,
                                                const std::string& points_file,
                                                const StrandReconstructionOptions& o,
                                                StrandReconstructionSummary* summary) {
  const int64_t t = SteadyNowNs();
  SegmentGrowthOptions segment_options = o.segments;
  segment_options.threads = o.threads;
  std::vector<StrandSegment> segments =
      GrowStrandSegments(points, segment_options, &summary->segments);
  summary->seconds_segments = SecondsSince(t);
  if (segments.empty()) {
    return InvalidArgument(points_file +
                           ": the points give no strand segment (too few or too sparse)");
  }
  return segments;
}

// Luo 2013 Sec. 5.2-7.3 on the undirected segments.
Result<StrandModel> RunLuo(const std::vector<OrientedPoint>& points,
                           const std::vector<StrandSegment>& segments, const HeadModel& head,
                           const StrandReconstructionOptions& o,
                           StrandReconstructionSummary* summary) {
  int64_t t = SteadyNowNs();
  std::vector<Ribbon> ribbons = CoverWithRibbons(points, segments, o.ribbons, &summary->ribbons);
  summary->seconds_ribbons = SecondsSince(t);
  t = SteadyNowNs();
  ConnectionOptions connections = o.connections;
  connections.threads = o.threads;
  std::vector<RibbonLink> links =
      ConnectRibbons(ribbons, segments, connections, &summary->connections);
  summary->seconds_connections = SecondsSince(t);
  t = SteadyNowNs();
  RibbonDirectionOptions ribbon_direction = o.ribbon_direction;
  ribbon_direction.threads = o.threads;
  summary->ribbon_direction = DirectRibbons(&ribbons, &links, &head, ribbon_direction);
  summary->seconds_direction = SecondsSince(t);
  t = SteadyNowNs();
  HR_ASSIGN_OR_RETURN(const std::vector<Wisp> wisps,
                      BuildWisps(points, ribbons, links, head, o.wisps, &summary->wisps));
  summary->seconds_wisps = SecondsSince(t);
  t = SteadyNowNs();
  StrandModel model;
  model.strands = SynthesizeStrands(wisps, o.strands, o.seed, o.synthesis);
  summary->seconds_growth = SecondsSince(t);
  SummariseStrands(model.strands, &summary->growth);
  model.segments = SegmentsAsStrands(segments);
  model.ribbons = IsocurvesAsStrands(ribbons);
  model.wisps = IsocurvesAsStrands(wisps);
  model.wisp_centres = WispCentres(wisps);
  model.structure = true;
  return model;
}

// Whether the points' view lists index `views`: the points stage's
// summary.json beside the points names its views in the order the lists
// index them. True when there is no summary to compare with (a bench's copy
// of the points).
bool PointViewsAre(const std::string& reconstruction_dir,
                   const std::vector<ReconstructionView>& views) {
  std::ifstream in(reconstruction_dir + "/summary.json");
  if (!in) return true;
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  if (summary.is_discarded() || !summary.contains("views") || !summary["views"].is_array())
    return true;
  const nlohmann::json& named = summary["views"];
  if (named.size() != views.size()) return false;
  for (size_t i = 0; i < views.size(); ++i)
    if (named[i].value("name", std::string()) != views[i].name) return false;
  return true;
}

// The views the points were seen from, where the points lie (`views` may be null).
struct StrandViews {
  const std::string& reconstruction_dir;
  const std::vector<ReconstructionView>* views;
};

// Where the cameras see through, for the helices' winding
// (helix_out_of_free_space); none without views or with the option off, and
// none (with a warning) when the points' view lists index other views or
// fewer views are given than the free space's min_views (nothing is free).
std::optional<FreeSpace> FreeSpaceFor(const std::vector<OrientedPoint>& points,
                                      const StrandViews& seen, const StrandGrowthOptions& growth) {
  if (seen.views == nullptr || !growth.helix_out_of_free_space) return std::nullopt;
  if (!PointViewsAre(seen.reconstruction_dir, *seen.views)) {
    LogWarning("strands: " + seen.reconstruction_dir +
               "/summary.json names other views than these; winding strands are not kept "
               "out of the free space (run the points stage with the same --views)");
    return std::nullopt;
  }
  const int min_views = growth.free_space.min_views;
  if (seen.views->size() < static_cast<size_t>(min_views)) {
    LogWarning("strands: " + std::to_string(seen.views->size()) +
               " views, fewer than the free space's min_views (" + std::to_string(min_views) +
               "): winding strands are not kept out of the free space (give " +
               std::to_string(min_views) + " views or more)");
    return std::nullopt;
  }
  return FreeSpace(*seen.views, points, growth.free_space);
}

// Bao & Qi 2017 on the segments directed by the MRF.
Result<StrandModel> RunBaoQi(const std::vector<OrientedPoint>& points,
                             std::vector<StrandSegment> segments, const HeadModel& head,
                             const std::vector<DirectedRoot>& roots,
                             const StrandReconstructionOptions& o, const SkinViews* skin,
                             const StrandViews& seen, StrandReconstructionSummary* summary) {
  int64_t t = SteadyNowNs();
  DirectionOptions direction = o.direction;
  direction.threads = o.threads;
  summary->direction = DirectSegments(&segments, &head, direction);
  summary->seconds_direction = SecondsSince(t);
  t = SteadyNowNs();
  HybridFieldOptions field_options = o.field;
  field_options.threads = o.threads;
  HR_ASSIGN_OR_RETURN(const HybridOrientationField field,
                      HybridOrientationField::Build(segments, roots, &head, field_options));
  summary->seconds_field = SecondsSince(t);
  t = SteadyNowNs();
  StrandGrowthOptions growth = o.growth;
  growth.threads = o.threads;
  // The curl is wound on only by the continuation past the seen strands.
  const CurlField curls = !growth.helix_continuation ? CurlField()
                          : o.given_curl.curly()     ? CurlField::Everywhere(o.given_curl)
                                                     : CurlField::Estimate(segments, growth.curl);
  summary->curl = curls.estimate();
  const SeenTips seen_tips = SeenTips::Find(segments, growth.seen_tips, &points);
  StrandModel model;
  // Only strands winding on a curl keep out of the free space.
  const std::optional<FreeSpace> free_space =
      curls.estimate().curl.curly() ? FreeSpaceFor(points, seen, growth) : std::nullopt;
  const FieldGrowth grow(field, &head, growth, skin, &curls, &seen_tips,
                         free_space ? &*free_space : nullptr);
  model.strands = grow.FromRoots(roots, &summary->growth);
  summary->growth.seen_tips = static_cast<int64_t>(seen_tips.size());
  summary->growth.seen_tip_ends_examined = static_cast<int64_t>(seen_tips.examined());
  grow.ThroughUncoveredSegments(segments, &model.strands, &summary->growth);
  summary->seconds_growth = SecondsSince(t);
  if (o.merging.run_mm > 0) {
    t = SteadyNowNs();
    model.strands = EndMergedStrands(model.strands, o.merging, &summary->merging);
    summary->seconds_merging = SecondsSince(t);
  }
  model.segments = SegmentsAsStrands(segments);
  return model;
}

// The roots bao-qi and naive grow from: o.strands on the scalp, leaving it
// at o.root_elevation_deg towards the direction MRF's down.
std::vector<DirectedRoot> ScalpRoots(const HeadModel& head, const StrandReconstructionOptions& o) {
  return SampleScalpRoots(head, o.strands, o.seed, o.root_elevation_deg,
                          o.direction.down.cast<double>());
}

// The baseline: no structure.
StrandModel RunNaive(const std::vector<OrientedPoint>& points, const HeadModel& head,
                     const std::vector<DirectedRoot>& roots, const StrandReconstructionOptions& o,
                     StrandReconstructionSummary* summary) {
  const int64_t t = SteadyNowNs();
  StrandGrowthOptions growth = o.growth;
  growth.threads = o.threads;
  const PointOrientationField field(points, o.segments.sigma_mm);
  StrandModel model;
  model.strands = GrowStrandsAlongPoints(field, roots, &head, growth, &summary->growth);
  summary->seconds_growth = SecondsSince(t);
  return model;
}

nlohmann::json LuoJson(const StrandReconstructionSummary& s) {
  return {{"ribbons",
           {{"count", s.ribbons.ribbons},
            {"covered_segments", s.ribbons.covered_segments},
            {"uncovered_segments", s.ribbons.uncovered_segments},
            {"mean_width", s.ribbons.mean_width},
            {"mean_length_mm", s.ribbons.mean_length_mm}}},
          {"connections",
           {{"pairs_tried", s.connections.pairs_tried},
            {"links", s.connections.links},
            {"rejected",
             {{"rms", s.connections.rejected_rms},
              {"curvature", s.connections.rejected_curvature},
              {"torsion", s.connections.rejected_torsion},
              {"overlap", s.connections.rejected_overlap},
              {"direction", s.connections.rejected_direction}}}}},
          {"ribbon_direction",
           {{"links", s.ribbon_direction.links},
            {"compatible_links", s.ribbon_direction.compatible_links},
            {"incompatible_links", s.ribbon_direction.incompatible_links},
            {"overlapping_pairs", s.ribbon_direction.overlapping_pairs},
            {"reversed", s.ribbon_direction.reversed},
            {"energy", s.ribbon_direction.energy}}},
          {"wisps",
           {{"count", s.wisps.wisps},
            {"connections", s.wisps.connections},
            {"removed_covered", s.wisps.removed_covered},
            {"removed_outliers", s.wisps.removed_outliers},
            {"attached", s.wisps.attached},
            {"unattached", s.wisps.unattached},
            {"interior", s.wisps.interior},
            {"covered_points", s.wisps.covered_points},
            {"mean_length_mm", s.wisps.mean_length_mm}}}};
}

}  // namespace

const char* StrandMethodName(StrandMethod method) {
  switch (method) {
    case StrandMethod::kNaive:
      return "naive";
    case StrandMethod::kLuo:
      return "luo";
    case StrandMethod::kBaoQi:
      break;
  }
  return "bao-qi";
}

Result<StrandMethod> ParseStrandMethod(const std::string& name) {
  for (const StrandMethod method :
       {StrandMethod::kBaoQi, StrandMethod::kNaive, StrandMethod::kLuo}) {
    if (name == StrandMethodName(method)) return method;
  }
  return InvalidArgument("strand method '" + name + "': expected bao-qi, naive or luo");
}

Status StrandReconstructionOptions::Check() const {
  if (strands < 1 || strands > 2000000) return InvalidArgument("strands must lie in 1..2000000");
  if (threads < 1) return InvalidArgument("threads must be at least 1");
  if (!(root_elevation_deg > 0 && root_elevation_deg <= 90))
    return InvalidArgument("root_elevation_deg must lie in (0, 90]");
  HR_RETURN_IF_ERROR(segments.Check().WithContext("segments"));
  HR_RETURN_IF_ERROR(direction.Check().WithContext("direction"));
  HR_RETURN_IF_ERROR(field.Check().WithContext("field"));
  HR_RETURN_IF_ERROR(growth.Check().WithContext("growth"));
  HR_RETURN_IF_ERROR(given_curl.Check().WithContext("given_curl"));
  HR_RETURN_IF_ERROR(merging.Check().WithContext("merging"));
  HR_RETURN_IF_ERROR(ribbons.Check().WithContext("ribbons"));
  HR_RETURN_IF_ERROR(connections.Check().WithContext("connections"));
  HR_RETURN_IF_ERROR(ribbon_direction.Check().WithContext("ribbon_direction"));
  HR_RETURN_IF_ERROR(wisps.Check().WithContext("wisps"));
  return synthesis.Check().WithContext("synthesis");
}

nlohmann::json StrandReconstructionSummary::ToJson() const {
  nlohmann::json j = {{"format", "hairrig-reconstruction-strands"},
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
                        {"stops",
                         {{"turn", segments.stops_turn},
                          {"hole", segments.stops_hole},
                          {"mls", segments.stops_mls},
                          {"length", segments.stops_length}}}}},
                      {"direction",
                       {{"links", direction.links},
                        {"overlaps_found", direction.overlaps_found},
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
                        {"stopped_where_hair_ends", growth.stopped_off_hair},
                        {"stopped_over_skin", growth.stopped_over_skin},
                        {"stopped_at_seen_tip", growth.stopped_seen_tip},
                        {"seen_tips", growth.seen_tips},
                        {"seen_tip_ends_examined", growth.seen_tip_ends_examined},
                        {"tips_trimmed_over_skin", growth.tips_trimmed_over_skin},
                        {"helix_moves_from_free_space", growth.helix_moves_from_free_space},
                        {"through_uncovered_segments",
                         {{"segments", growth.cover_candidates},
                          {"strands", growth.cover_strands},
                          {"grafted", growth.cover_grafted},
                          {"no_root", growth.cover_no_root},
                          {"trimmed_away", growth.cover_trimmed_away}}},
                        {"dropped_short", growth.dropped_short}}},
                      {"curl", curl.ToJson()},
                      // EndMergedStrands after growth: "strands" counts what was grown.
                      {"merging",
                       {{"ended_where_merged", merging.strands_ended},
                        {"dropped_merged_from_root", merging.strands_dropped},
                        {"vertices_removed", merging.vertices_removed}}},
                      {"seconds",
                       {{"segments", seconds_segments},
                        {"direction", seconds_direction},
                        {"field", seconds_field},
                        {"growth", seconds_growth},
                        {"merging", seconds_merging},
                        {"ribbons", seconds_ribbons},
                        {"connections", seconds_connections},
                        {"wisps", seconds_wisps},
                        {"total", seconds_total}}},
                      {"output_dir", output_dir}};
  if (method == StrandMethodName(StrandMethod::kLuo)) j.update(LuoJson(*this));
  return j;
}

std::string StrandReconstructionSummary::BriefReport() const {
  const bool luo = method == StrandMethodName(StrandMethod::kLuo);
  std::ostringstream s;
  s.precision(3);
  s << "strands (" << method << ", head: " << head_source << "): " << growth.strands
    << " strands, mean " << growth.mean_length_mm << " mm, from " << segments.segments
    << " segments (mean " << segments.mean_length_mm << " mm; ";
  if (luo) {
    s << ribbons.ribbons << " ribbons, " << connections.links << " links, "
      << ribbon_direction.reversed << " ribbons reversed by the direction MRF) of " << points
      << " points\n";
    s << "  wisps: " << wisps.wisps << " (" << wisps.attached << " attached, " << wisps.interior
      << " interior; " << wisps.connections << " connections; removed " << wisps.removed_covered
      << " covered, " << wisps.removed_outliers << " outliers), mean " << wisps.mean_length_mm
      << " mm\n";
    s << "  time: segments " << seconds_segments << " s, ribbons " << seconds_ribbons
      << " s, connections " << seconds_connections << " s, direction " << seconds_direction
      << " s, wisps " << seconds_wisps << " s, synthesis " << seconds_growth << " s, total "
      << seconds_total << " s\n";
    s << "  written: " << output_dir
      << "/strands.{ply,hair,data}, segments.ply, ribbons.ply, wisps.ply, summary.json\n";
    return s.str();
  }
  s << direction.reversed << " reversed by the direction MRF) of " << points << " points\n";
  if (curl.curl.curly()) {
    s << "  curls: radius " << curl.curl.radius_mm << " mm, pitch " << curl.curl.pitch_mm << " mm, "
      << (curl.curl.handedness > 0 ? "right" : "left") << "-handed, ";
    if (curl.arcs == 0) {
      s << "given\n";
    } else {
      s << "from " << curl.arcs << " seen arcs (" << 100 * curl.arc_share
        << " % of the seen length; " << 100 * curl.right_handed_share << " % of it right-handed, "
        << 100 * curl.local_handedness_agreement << " % turning as the arcs beside it), wound "
        << (curl.region == CurlRegion::kWholeHair ? "wherever strands grow" : "near the seen arcs")
        << "\n";
    }
  } else if (curl.arcs > 0) {
    s << "  no curls: " << curl.arcs << " seen arcs, " << 100 * curl.arc_share
      << " % of the seen length, " << 100 * curl.local_handedness_agreement
      << " % of it turning as the arcs beside it\n";
  }
  if (growth.stopped_over_skin + growth.tips_trimmed_over_skin > 0) {
    s << "  ended in front of skin the views see: " << growth.stopped_over_skin
      << " strands; tips trimmed back from skin: " << growth.tips_trimmed_over_skin << "\n";
  }
  if (growth.seen_tip_ends_examined > 0) {
    s << "  ended where a seen strand ends: " << growth.stopped_seen_tip << " strands, at "
      << growth.seen_tips << " of the " << growth.seen_tip_ends_examined
      << " seen strands' tip ends (no other seen strand carries on from them)\n";
  }
  if (growth.cover_candidates > 0) {
    s << "  through seen strands the others missed: " << growth.cover_strands << " strands for "
      << growth.cover_candidates << " uncovered segments (" << growth.cover_grafted
      << " grafted on a strand nearby; " << growth.cover_no_root << " with no way to the scalp";
    if (growth.cover_trimmed_away > 0)
      s << "; " << growth.cover_trimmed_away << " over skin from root to tip";
    s << ")\n";
  }
  if (merging.strands_ended + merging.strands_dropped > 0) {
    s << "  merged: " << merging.strands_ended
      << " strands ended where they joined an earlier one, " << merging.strands_dropped
      << " dropped (joined from the root), " << merging.vertices_removed << " vertices removed\n";
  }
  s << "  time: segments " << seconds_segments << " s, direction " << seconds_direction
    << " s, field " << seconds_field << " s, growth " << seconds_growth << " s, ";
  if (seconds_merging > 0) s << "merging " << seconds_merging << " s, ";
  s << "total " << seconds_total << " s\n";
  s << "  written: " << output_dir << "/strands.{ply,hair,data}, segments.ply, summary.json\n";
  return s.str();
}

Result<StrandReconstructionSummary> ReconstructStrands(
    const std::string& reconstruction_dir, const HeadSpec& head_spec,
    const std::string& head_source, const StrandReconstructionOptions& o, const SkinViews* skin,
    const std::vector<ReconstructionView>* views) {
  HR_RETURN_IF_ERROR(o.Check());
  const int64_t start = SteadyNowNs();
  StrandReconstructionSummary summary;
  summary.method = StrandMethodName(o.method);
  summary.head_source = head_source;
  summary.output_dir = reconstruction_dir + "/strands";
  const std::string points_file = reconstruction_dir + "/points.ply";
  if (!std::filesystem::exists(points_file)) {
    return NotFound(points_file +
                    ": no oriented points; run `hairrig reconstruct DIR --stage points` first");
  }
  HR_ASSIGN_OR_RETURN(const std::vector<OrientedPoint> points, ReadPointCloudPly(points_file));
  summary.points = static_cast<int64_t>(points.size());
  HR_ASSIGN_OR_RETURN(const std::unique_ptr<HeadModel> head, HeadModel::Build(head_spec));

  StrandModel model;
  if (o.method == StrandMethod::kNaive) {
    model = RunNaive(points, *head, ScalpRoots(*head, o), o, &summary);
  } else {
    HR_ASSIGN_OR_RETURN(std::vector<StrandSegment> segments,
                        GrowSegments(points, points_file, o, &summary));
    if (o.method == StrandMethod::kLuo) {
      HR_ASSIGN_OR_RETURN(model, RunLuo(points, segments, *head, o, &summary));
    } else {
      HR_ASSIGN_OR_RETURN(
          model, RunBaoQi(points, std::move(segments), *head, ScalpRoots(*head, o), o, skin,
                          StrandViews{reconstruction_dir, views}, &summary));
    }
  }
  summary.seconds_total = SecondsSince(start);
  HR_RETURN_IF_ERROR(WriteOutputs(summary.output_dir, model, summary));
  return summary;
}

}  // namespace hairrig
