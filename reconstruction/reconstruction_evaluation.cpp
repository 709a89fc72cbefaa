#include "reconstruction/reconstruction_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <utility>

#include "core/geometry_json.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/json_file.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/statistics.h"
#include "core/strand_io.h"
#include "core/truth_maps.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/strand_preview.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

struct ReconstructedViews {
  std::vector<std::string> names;
  int stride_px = 1;
  double min_confidence = 0;
  Rigid3d object_from_box;
};

Result<ReconstructedViews> ReadSummary(const std::string& dir) {
  const std::string path = dir + "/summary.json";
  HR_ASSIGN_OR_RETURN(nlohmann::json root,
                      ReadJsonFile(path, "run `hairrig reconstruct` on the capture first"));
  if (!root.is_object() || !root.contains("views") || !root["views"].is_array() ||
      !root.contains("stride_px") || !root["stride_px"].is_number_integer())
    return CorruptData(path + ": needs views (an array) and stride_px (an integer)");
  ReconstructedViews out;
  out.stride_px = std::max(1, root["stride_px"].get<int>());
  const nlohmann::json confidence = root.value("min_orientation_confidence", nlohmann::json(0.0));
  out.min_confidence = confidence.is_number() ? confidence.get<double>() : 0.0;
  if (!root.contains("object_from_box"))
    return CorruptData(
        path +
        ": no object_from_box: only a capture's reconstruction can be compared with its truth");
  HR_ASSIGN_OR_RETURN(out.object_from_box,
                      PoseFromJson(root["object_from_box"], path + ": object_from_box"));
  for (const nlohmann::json& v : root["views"]) {
    if (!v.is_object() || !v.contains("name") || !v["name"].is_string())
      return CorruptData(path + ": every view needs a name");
    out.names.push_back(v["name"].get<std::string>());
  }
  return out;
}

// The capture's view number at the start of a view's name ("012_SIM-CAM-UPPER").
Result<int> ViewNumber(const std::string& name) {
  int view = -1, used = 0;
  if (std::sscanf(name.c_str(), "%d%n", &view, &used) != 1 || used == 0 || view < 0)
    return CorruptData("view '" + name + "' does not start with its view number");
  return view;
}

struct ViewResult {
  Status status;
  ViewReconstructionAccuracy accuracy;
  std::vector<double> depth_errors;
  cv::Mat1f true_depth;
  cv::Mat1b true_bare_skin;  // the true head label with no fibre over it
};

ViewResult EvaluateView(const std::string& dir, const std::string& name,
                        const ReconstructedViews& recon, const CaptureTruth& truth) {
  ViewResult r;
  r.accuracy.name = name;
  auto run = [&]() -> Status {
    HR_ASSIGN_OR_RETURN(r.accuracy.view, ViewNumber(name));
    if (!truth.views.count(r.accuracy.view))
      return NotFound("view " + name + " has no ground truth");
    HR_ASSIGN_OR_RETURN(const ViewTruthMaps maps,
                        ReadVerifiedViewTruthMaps(truth, r.accuracy.view));
    const cv::Mat true_hair = maps.label == ViewTruthMaps::kHair;
    HR_ASSIGN_OR_RETURN(const cv::Mat label,
                        ReadImageFile(dir + "/masks/" + name + "_label.png", cv::IMREAD_UNCHANGED));
    HR_ASSIGN_OR_RETURN(r.accuracy.mask_iou, MaskIoU(label == 3, true_hair));
    HR_ASSIGN_OR_RETURN(
        const cv::Mat angle,
        ReadImageFile(dir + "/orientation/" + name + "_angle.png", cv::IMREAD_UNCHANGED));
    HR_ASSIGN_OR_RETURN(
        const cv::Mat confidence,
        ReadImageFile(dir + "/orientation/" + name + "_confidence.png", cv::IMREAD_UNCHANGED));
    OrientationMap map;
    angle.convertTo(map.angle_deg, CV_32F, 0.01);
    map.angle_deg.setTo(std::numeric_limits<float>::quiet_NaN(), angle == 65535);
    confidence.convertTo(map.confidence, CV_32F, 1.0 / 65535);
    HR_ASSIGN_OR_RETURN(
        r.accuracy.orientation,
        MeasureOrientation(map, maps.orientation_deg, true_hair, recon.min_confidence));
    HR_ASSIGN_OR_RETURN(const cv::Mat depth,
                        ReadImageFile(dir + "/depth/" + name + "_depth.png", cv::IMREAD_UNCHANGED));
    if (depth.type() != CV_16U)
      return CorruptData(dir + "/depth/" + name + "_depth.png: not a 16-bit PNG");
    for (int gy = 0; gy < depth.rows; ++gy) {
      for (int gx = 0; gx < depth.cols; ++gx) {
        const int u = gx * recon.stride_px, v = gy * recon.stride_px;
        const uint16_t d = depth.at<uint16_t>(gy, gx);
        if (d == 0 || u >= maps.label.cols || v >= maps.label.rows || !true_hair.at<uint8_t>(v, u))
          continue;
        r.depth_errors.push_back(std::abs(d / 20.0 - maps.depth_mm.at<float>(v, u)));
      }
    }
    r.accuracy.depth_cells = static_cast<int>(r.depth_errors.size());
    double sum = 0;
    for (double e : r.depth_errors) sum += e;
    r.accuracy.depth_mean_mm =
        r.depth_errors.empty() ? 0 : sum / static_cast<double>(r.depth_errors.size());
    r.accuracy.depth_median_mm = Median(r.depth_errors);
    r.true_depth = maps.depth_mm;
    // A fibre covers about a tenth of a pixel at the rig's resolution.
    constexpr double kBareAlpha = 0.02;
    r.true_bare_skin = (maps.label == ViewTruthMaps::kHead) & (maps.hair_alpha < kBareAlpha);
    return Status::Ok();
  };
  r.status = run();
  return r;
}

// A true camera with its view's true depth and label maps.
struct TrueCamera {
  std::array<double, CameraIntrinsics::kNumParams> params;
  Rigid3d cam_from_turntable;
  const cv::Mat1f* depth;
  const cv::Mat1b* bare_skin;
};

std::vector<TrueCamera> TrueCameras(const CaptureTruth& truth,
                                    const std::map<int, cv::Mat1f>& depth_maps,
                                    const std::map<int, cv::Mat1b>& bare_skin) {
  std::vector<TrueCamera> cameras;
  const Rigid3d box_from_turntable = truth.turntable_from_box.Inverse();
  for (const auto& [view, depth] : depth_maps) {
    const CaptureTruth::View& v = truth.views.at(view);
    cameras.push_back({v.intrinsics.ToParams(), v.cam_from_box * box_from_turntable, &depth,
                       &bare_skin.at(view)});
  }
  return cameras;
}

// Where p (true turntable frame) falls in a camera: its depth (mm) and the
// nearest pixel; false behind the camera or outside the image.
bool ProjectToPixel(const TrueCamera& c, const Eigen::Vector3d& p, double* depth_mm, int* x,
                    int* y) {
  const Eigen::Vector3d q = c.cam_from_turntable * p;
  if (q.z() <= 1) return false;
  double uv[2];
  ProjectCamPoint(c.params.data(), q.data(), uv);
  *x = static_cast<int>(std::lround(uv[0]));
  *y = static_cast<int>(std::lround(uv[1]));
  *depth_mm = q.z();
  return *x >= 0 && *y >= 0 && *x < c.depth->cols && *y < c.depth->rows;
}

// How many true cameras see each sample: within tolerance of their true depth maps.
std::vector<int> VisibleCounts(const std::vector<OrientedSample>& samples,
                               const std::vector<TrueCamera>& cameras, double tolerance_mm,
                               int threads) {
  std::vector<int> counts(samples.size(), 0);
  ParallelFor(samples.size(), threads, [&] {
    return [&](size_t i) {
      const Eigen::Vector3d p = samples[i].position_mm.cast<double>();
      for (const TrueCamera& c : cameras) {
        double depth;
        int x, y;
        if (ProjectToPixel(c, p, &depth, &x, &y) &&
            std::abs((*c.depth)(y, x) - depth) <= tolerance_mm)
          ++counts[i];
      }
    };
  });
  return counts;
}

// Of the (strand point, camera) pairs where the point lies in the image and
// not behind the true front surface by more than tolerance_mm (seen, or in
// front of what is seen), the share whose pixel shows the true head's bare
// skin, the point lying below the true head's hairline (`head` may be null:
// anywhere): strand points in front of the bare face, ears and neck, where
// the truth has no hair. Above the hairline the roots stand on the scalp
// where it shows between them. Every `step`-th point of the set.
double InFrontOfTrueSkinShare(const StrandSet& strands, const std::vector<TrueCamera>& cameras,
                              const HeadModel* head, double tolerance_mm, size_t step,
                              int threads) {
  const size_t n = (strands.points_mm.size() + step - 1) / step;
  // Sums per chunk of samples, added up after the parallel loop.
  constexpr size_t kChunk = 4096;
  const size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<int64_t> seen(chunks, 0), over_skin(chunks, 0);
  ParallelFor(chunks, threads, [&] {
    return [&](size_t chunk) {
      for (size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
        const Eigen::Vector3d p = strands.points_mm[i * step].cast<double>();
        const bool below_hairline = head == nullptr || !head->AboveHairline(p);
        for (const TrueCamera& c : cameras) {
          double depth;
          int x, y;
          if (!ProjectToPixel(c, p, &depth, &x, &y) || depth > (*c.depth)(y, x) + tolerance_mm)
            continue;
          ++seen[chunk];
          over_skin[chunk] += below_hairline && (*c.bare_skin)(y, x) != 0;
        }
      }
    };
  });
  int64_t seen_sum = 0, skin_sum = 0;
  for (size_t k = 0; k < chunks; ++k) seen_sum += seen[k], skin_sum += over_skin[k];
  return seen_sum > 0 ? static_cast<double>(skin_sum) / static_cast<double>(seen_sum) : 0.0;
}

// The reconstruction's points as samples in the true turntable frame.
Result<std::vector<OrientedSample>> EstimateSamples(const std::string& dir,
                                                    const Rigid3d& truth_from_estimate) {
  const Eigen::Matrix3f rotation = truth_from_estimate.RotationMatrix().cast<float>();
  HR_ASSIGN_OR_RETURN(const std::vector<OrientedPoint> points,
                      ReadPointCloudPly(dir + "/points.ply"));
  std::vector<OrientedSample> samples;
  samples.reserve(points.size());
  for (const OrientedPoint& p : points) {
    samples.push_back({(truth_from_estimate * p.position_mm.cast<double>()).cast<float>(),
                       rotation * p.direction});
  }
  return samples;
}

// `strands` with every point mapped by to_from_strands.
StrandSet TransformedStrands(const StrandSet& strands, const Rigid3d& to_from_strands) {
  StrandSet out = strands;
  for (Eigen::Vector3f& p : out.points_mm) p = (to_from_strands * p.cast<double>()).cast<float>();
  return out;
}

// The reconstruction's strands against the true ones, if it has any, into
// out->strands, their turntable preview beside the truth's (out->
// strands_preview) and, with the truth's skin, their share over it.
Status EvaluateStrandsFile(const std::string& dir, const std::string& capture_dir,
                           const CaptureTruth& truth, const Rigid3d& truth_from_estimate,
                           const StrandSet& true_strands,
                           const std::vector<OrientedSample>& truth_samples,
                           const std::vector<uint32_t>& truth_sample_strand,
                           const std::vector<uint8_t>& visible,
                           const std::vector<TrueCamera>& cameras,
                           const ReconstructionEvalOptions& options,
                           ReconstructionEvaluation* out) {
  const std::string path = (fs::path(dir) / "strands" / "strands.ply").string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return Status::Ok();
  HR_ASSIGN_OR_RETURN(const StrandSet strands, ReadStrands(path));
  std::unique_ptr<HeadModel> head;
  if (truth.head) {
    auto built = HeadModel::Build(*truth.head);
    if (!built.ok()) return built.status().WithContext("the true head of " + capture_dir);
    head = std::move(built).value();
  }
  StrandEvalOptions strand_options;
  strand_options.sample_step_mm = options.truth_step_mm;
  strand_options.threads = options.threads;
  const StrandSet in_truth_frame = TransformedStrands(strands, truth_from_estimate);
  auto evaluation = EvaluateStrands(in_truth_frame, true_strands, truth_samples,
                                    truth_sample_strand, visible, head.get(), strand_options);
  if (!evaluation.ok()) return evaluation.status().WithContext(path);
  HR_ASSIGN_OR_RETURN(const cv::Mat preview,
                      RenderStrandPreview({&in_truth_frame, &true_strands},
                                          {"reconstruction", "ground truth"}, {}));
  // A capture that cannot be written to (an archive) is still scored.
  const std::string preview_file = (fs::path(dir) / "strands" / "preview_truth.jpg").string();
  const Status written = WriteImageAtomic(preview_file, preview);
  if (written.ok()) {
    out->strands_preview = preview_file;
  } else {
    LogWarning("eval reconstruction: no preview beside the truth: " + written.ToString());
  }
  out->strands = std::move(evaluation).value();
  constexpr size_t kSkinSampleStep = 2;
  out->strands_over_true_skin =
      InFrontOfTrueSkinShare(in_truth_frame, cameras, head.get(), options.visibility_tolerance_mm,
                             kSkinSampleStep, options.threads);
  out->truth_over_true_skin =
      InFrontOfTrueSkinShare(true_strands, cameras, head.get(), options.visibility_tolerance_mm,
                             kSkinSampleStep, options.threads);
  return Status::Ok();
}

}  // namespace

Status ReconstructionEvalOptions::Check() const {
  if (!(truth_step_mm >= 0.1)) return InvalidArgument("eval truth_step_mm must be at least 0.1");
  if (!(visibility_tolerance_mm > 0))
    return InvalidArgument("eval visibility_tolerance_mm must be positive");
  if (min_visible_views < 1) return InvalidArgument("eval min_visible_views must be at least 1");
  if (threads < 1) return InvalidArgument("eval threads must be at least 1");
  return Status::Ok();
}

namespace {

// The folder scored: options.reconstruction_dir, or <capture>/reconstruction.
std::string ReconstructionDir(const std::string& capture_dir,
                              const ReconstructionEvalOptions& options) {
  return options.reconstruction_dir.empty() ? (fs::path(capture_dir) / "reconstruction").string()
                                            : options.reconstruction_dir;
}

}  // namespace

Result<ReconstructionEvaluation> EvaluateReconstruction(const std::string& capture_dir,
                                                        const ReconstructionEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string dir = ReconstructionDir(capture_dir, options);
  HR_ASSIGN_OR_RETURN(const CaptureTruth truth, ReadCaptureTruth(capture_dir));
  HR_ASSIGN_OR_RETURN(const ReconstructedViews recon, ReadSummary(dir));

  std::vector<ViewResult> per_view(recon.names.size());
  ParallelFor(recon.names.size(), options.threads, [&] {
    return [&](size_t v) { per_view[v] = EvaluateView(dir, recon.names[v], recon, truth); };
  });
  ReconstructionEvaluation out;
  std::vector<double> ious, orientation_medians, orientation_p90s, depth_errors;
  int64_t hair = 0, kept = 0;
  std::map<int, cv::Mat1f> depth_maps;
  std::map<int, cv::Mat1b> bare_skin;
  for (ViewResult& r : per_view) {
    HR_RETURN_IF_ERROR(r.status);
    out.views.push_back(r.accuracy);
    ious.push_back(r.accuracy.mask_iou);
    orientation_medians.push_back(r.accuracy.orientation.median_error_deg);
    orientation_p90s.push_back(r.accuracy.orientation.p90_error_deg);
    hair += r.accuracy.orientation.hair_pixels;
    kept += r.accuracy.orientation.kept_pixels;
    depth_errors.insert(depth_errors.end(), r.depth_errors.begin(), r.depth_errors.end());
    depth_maps[r.accuracy.view] = r.true_depth;
    bare_skin[r.accuracy.view] = r.true_bare_skin;
  }
  if (!ious.empty()) {
    out.mask_iou_median = Median(ious);
    out.mask_iou_worst = *std::min_element(ious.begin(), ious.end());
    out.orientation_median_deg = Median(orientation_medians);
    out.orientation_p90_deg = Median(orientation_p90s);
    out.orientation_kept_fraction =
        hair > 0 ? static_cast<double>(kept) / static_cast<double>(hair) : 0;
  }
  double sum = 0;
  for (double e : depth_errors) sum += e;
  out.depth_mean_mm = depth_errors.empty() ? 0 : sum / static_cast<double>(depth_errors.size());
  out.depth_median_mm = Median(std::move(depth_errors));

  const Rigid3d truth_from_estimate = truth.turntable_from_box * recon.object_from_box.Inverse();
  HR_ASSIGN_OR_RETURN(const std::vector<OrientedSample> estimate,
                      EstimateSamples(dir, truth_from_estimate));
  HR_RETURN_IF_ERROR(VerifyTruthFile(truth, truth.strands_file));
  HR_ASSIGN_OR_RETURN(const StrandSet true_strands, ReadStrands(truth.strands_file));
  // The true strands sampled, and their samples tested for visibility, once for the points and the
  // strands.
  std::vector<uint32_t> truth_sample_strand;
  const std::vector<OrientedSample> all_truth =
      SampleStrands(true_strands, options.truth_step_mm, &truth_sample_strand);
  const std::vector<TrueCamera> cameras = TrueCameras(truth, depth_maps, bare_skin);
  const std::vector<int> counts =
      VisibleCounts(all_truth, cameras, options.visibility_tolerance_mm, options.threads);
  std::vector<uint8_t> visible(all_truth.size(), 0);
  for (size_t i = 0; i < all_truth.size(); ++i)
    visible[i] = static_cast<uint8_t>(counts[i] >= options.min_visible_views);
  out.points = static_cast<int64_t>(estimate.size());
  out.truth_samples = static_cast<int64_t>(all_truth.size());
  SampleMatchOptions match;
  match.threads = options.threads;
  SubsetMatchScores scores =
      MatchSamplesAndSubset(estimate, all_truth, visible, DefaultMatchThresholds(), match);
  out.visible_truth_samples = scores.subset_size;
  out.all = std::move(scores.all);
  out.visible = std::move(scores.subset);
  HR_RETURN_IF_ERROR(EvaluateStrandsFile(options.strands_dir.empty() ? dir : options.strands_dir,
                                         capture_dir, truth, truth_from_estimate, true_strands,
                                         all_truth, truth_sample_strand, visible, cameras, options,
                                         &out));
  return out;
}

namespace {

// The true samples on the visible surface, in the true turntable frame.
Result<std::vector<OrientedSample>> VisibleTruthSamples(const CaptureTruth& truth,
                                                        const ReconstructionEvalOptions& options) {
  std::map<int, cv::Mat1f> depth_maps;
  std::map<int, cv::Mat1b> no_skin;
  for (const auto& [view, unused] : truth.views) {
    HR_ASSIGN_OR_RETURN(const ViewTruthMaps maps, ReadVerifiedViewTruthMaps(truth, view));
    depth_maps[view] = maps.depth_mm;
    no_skin[view] = cv::Mat1b();
  }
  HR_RETURN_IF_ERROR(VerifyTruthFile(truth, truth.strands_file));
  HR_ASSIGN_OR_RETURN(const StrandSet true_strands, ReadStrands(truth.strands_file));
  const std::vector<OrientedSample> all = SampleStrands(true_strands, options.truth_step_mm);
  const std::vector<int> counts = VisibleCounts(all, TrueCameras(truth, depth_maps, no_skin),
                                                options.visibility_tolerance_mm, options.threads);
  std::vector<OrientedSample> visible;
  for (size_t i = 0; i < all.size(); ++i)
    if (counts[i] >= options.min_visible_views) visible.push_back(all[i]);
  return visible;
}

// Each point's direction replaced by the nearest visible true sample's within 2 mm.
void TakeTrueDirections(const std::vector<OrientedSample>& visible_in_estimate,
                        std::vector<OrientedPoint>* points, int threads) {
  std::vector<OrientedSample> own;
  own.reserve(points->size());
  for (const OrientedPoint& p : *points) own.push_back({p.position_mm, p.direction});
  SampleMatchOptions match;
  match.threads = threads;
  constexpr MatchThreshold kAnyDirectionWithin2mm{2.0, 181};
  const std::vector<int64_t> nearest =
      NearestMatches(visible_in_estimate, own, kAnyDirectionWithin2mm, match);
  for (size_t i = 0; i < points->size(); ++i)
    if (nearest[i] >= 0) (*points)[i].direction = visible_in_estimate[nearest[i]].direction;
}

}  // namespace

Result<std::vector<OrientedPoint>> PointsFromTruth(const std::string& capture_dir,
                                                   TruthPointsKind kind,
                                                   const ReconstructionEvalOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  const std::string dir = ReconstructionDir(capture_dir, options);
  HR_ASSIGN_OR_RETURN(const CaptureTruth truth, ReadCaptureTruth(capture_dir));
  HR_ASSIGN_OR_RETURN(const ReconstructedViews recon, ReadSummary(dir));
  HR_ASSIGN_OR_RETURN(std::vector<OrientedPoint> points, ReadPointCloudPly(dir + "/points.ply"));
  HR_ASSIGN_OR_RETURN(std::vector<OrientedSample> visible, VisibleTruthSamples(truth, options));
  const Rigid3d estimate_from_truth =
      (truth.turntable_from_box * recon.object_from_box.Inverse()).Inverse();
  const Eigen::Matrix3f rotation = estimate_from_truth.RotationMatrix().cast<float>();
  for (OrientedSample& s : visible) {
    s.position_mm = (estimate_from_truth * s.position_mm.cast<double>()).cast<float>();
    s.direction = rotation * s.direction;
  }
  if (kind == TruthPointsKind::kTrueDirections) {
    TakeTrueDirections(visible, &points, options.threads);
    return points;
  }
  const double keep =
      visible.empty()
          ? 0
          : std::min(1.0, static_cast<double>(points.size()) / static_cast<double>(visible.size()));
  std::mt19937_64 random(1);
  std::bernoulli_distribution kept(keep);
  std::vector<OrientedPoint> out;
  for (const OrientedSample& s : visible)
    if (kept(random)) out.push_back({s.position_mm, s.direction, 1.0f, {}});
  return out;
}

nlohmann::json ReconstructionEvaluation::ToJson() const {
  nlohmann::json views_json = nlohmann::json::array();
  for (const ViewReconstructionAccuracy& v : views) {
    views_json.push_back({{"name", v.name},
                          {"view", v.view},
                          {"mask_iou", v.mask_iou},
                          {"orientation_median_deg", v.orientation.median_error_deg},
                          {"orientation_p90_deg", v.orientation.p90_error_deg},
                          {"orientation_kept_fraction", v.orientation.kept_fraction},
                          {"depth_cells", v.depth_cells},
                          {"depth_mean_mm", v.depth_mean_mm},
                          {"depth_median_mm", v.depth_median_mm}});
  }
  nlohmann::json j = {{"stage", "reconstruction"},
                      {"masks", {{"iou_median", mask_iou_median}, {"iou_worst", mask_iou_worst}}},
                      {"orientation",
                       {{"median_deg", orientation_median_deg},
                        {"p90_deg", orientation_p90_deg},
                        {"kept_fraction", orientation_kept_fraction}}},
                      {"depth", {{"median_mm", depth_median_mm}, {"mean_mm", depth_mean_mm}}},
                      {"points",
                       {{"count", points},
                        {"truth_samples", truth_samples},
                        {"visible_truth_samples", visible_truth_samples},
                        {"visible_surface", ScoresToJson(visible)},
                        {"all_strands", ScoresToJson(all)}}},
                      {"views", views_json}};
  if (strands) {
    j["strands"] = strands->ToJson();
    j["strands"]["preview"] = strands_preview;
    if (strands_over_true_skin) {
      j["strands"]["over_true_skin_share"] = *strands_over_true_skin;
      j["strands"]["truth_over_true_skin_share"] = truth_over_true_skin.value_or(0);
    }
  }
  return j;
}

std::string ReconstructionEvaluation::BriefReport() const {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << "masks: hair IoU median " << mask_iou_median << ", worst " << mask_iou_worst << " ("
    << views.size() << " views)\n";
  s.precision(2);
  s << "orientation: median error " << orientation_median_deg << " deg, 90th percentile "
    << orientation_p90_deg << " deg (medians over views), " << 100 * orientation_kept_fraction
    << " % of hair pixels kept\n";
  s << "depth: median error " << depth_median_mm << " mm, mean " << depth_mean_mm
    << " mm (stereo grid, true hair)\n";
  s << "points: " << points << " against " << truth_samples << " true samples ("
    << visible_truth_samples << " seen by >= 2 cameras)\n";
  s.precision(3);
  for (size_t k = 0; k < visible.size(); ++k) {
    s << "  (" << visible[k].threshold.distance_mm << " mm, " << visible[k].threshold.angle_deg
      << " deg): precision " << visible[k].precision << ", visible-surface recall "
      << visible[k].recall << " (F1 " << visible[k].f1 << "), all-strands recall " << all[k].recall
      << "\n";
  }
  if (strands) s << strands->BriefReport();
  if (strands_over_true_skin) {
    s.precision(2);
    s << "  over skin: " << 100 * *strands_over_true_skin
      << " % of strand points seen by a camera lie in front of the true skin (the true strands: "
      << 100 * truth_over_true_skin.value_or(0) << " %)\n";
  }
  if (!strands_preview.empty()) s << "wrote: " << strands_preview << "\n";
  return s.str();
}

}  // namespace hairrig
