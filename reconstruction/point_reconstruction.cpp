#include "reconstruction/point_reconstruction.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/clock.h"
#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/image_file.h"
#include "core/json_file.h"
#include "core/parallel.h"
#include "core/statistics.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// The median of `values` where `mask` is non-zero (0 for an empty mask).
double MedianOver(const cv::Mat1f& values, const cv::Mat1b& mask) {
  std::vector<float> kept;
  for (int y = 0; y < values.rows; ++y)
    for (int x = 0; x < values.cols; ++x)
      if (mask(y, x)) kept.push_back(values(y, x));
  return Median(std::move(kept));
}

// A view after segmentation and orientation: what the stereo and the report need.
struct PreparedView {
  std::string why_not;       // non-empty: left out
  Status written;            // writing the view's masks and orientation maps
  uint16_t input_index = 0;  // in ReconstructionInput::views
  MvsView mvs;
  cv::Mat1b silhouette;
  cv::Mat image;  // BGR, for the report
  ViewPointsSummary summary;
};

cv::Mat1w ToUInt16(const cv::Mat1f& values, float scale, float missing_value, uint16_t missing) {
  cv::Mat1w out(values.size(), missing);
  for (int y = 0; y < values.rows; ++y)
    for (int x = 0; x < values.cols; ++x) {
      const float v = values(y, x);
      if (std::isfinite(v) && v != missing_value)
        out(y, x) = static_cast<uint16_t>(std::clamp(std::lround(v * scale), 0L, 65534L));
    }
  return out;
}

Status WriteSegmentation(const std::string& dir, const std::string& name,
                         const HairSegmentation& s) {
  HR_RETURN_IF_ERROR(WriteImageAtomic(dir + "/" + name + "_label.png", s.label));
  cv::Mat1w alpha;
  s.hair_alpha.convertTo(alpha, CV_16U, 65535.0);
  return WriteImageAtomic(dir + "/" + name + "_alpha.png", alpha);
}

Status WriteOrientation(const std::string& dir, const std::string& name, const OrientationMap& map,
                        bool picture) {
  HR_RETURN_IF_ERROR(WriteImageAtomic(dir + "/" + name + "_angle.png",
                                      ToUInt16(map.angle_deg, 100.f, -1.f, uint16_t{65535})));
  cv::Mat1w confidence;
  map.confidence.convertTo(confidence, CV_16U, 65535.0);
  HR_RETURN_IF_ERROR(WriteImageAtomic(dir + "/" + name + "_confidence.png", confidence));
  if (!picture) return Status::Ok();
  return WriteImageAtomic(dir + "/" + name + ".jpg", OrientationPicture(map),
                          {cv::IMWRITE_JPEG_QUALITY, 90});
}

// Reads a view's image into p->image (once: the second pass of
// SegmentCaptureViews reuses it) and segments it; the error says why a view
// cannot be used.
Result<HairSegmentation> SegmentView(const ReconstructionView& view,
                                     const PointReconstructionOptions& options,
                                     const SkinChromaticity* capture_skin, PreparedView* p) {
  try {
    if (p->image.empty()) {
      Result<cv::Mat> image = ReadImageFile(view.image_path, cv::IMREAD_COLOR);
      if (!image.ok()) return image.status();
      p->image = *std::move(image);
    }
    if (p->image.cols != view.camera.width_px || p->image.rows != view.camera.height_px) {
      return FailedPrecondition(view.image_path + ": " + std::to_string(p->image.cols) + "x" +
                                std::to_string(p->image.rows) + " px, its camera is " +
                                std::to_string(view.camera.width_px) + "x" +
                                std::to_string(view.camera.height_px));
    }
    return SegmentHair(p->image, view.not_hair_px, options.segmentation, capture_skin);
  } catch (const std::exception& e) {  // OpenCV's on memory exhaustion, in a worker thread
    return FailedPrecondition(view.image_path + ": " + e.what());
  }
}

// Filters one segmented view and writes its masks and maps; a view that
// cannot be used says why.
void PrepareView(const ReconstructionView& view, const PointReconstructionOptions& options,
                 const std::string& out_dir, Result<HairSegmentation> seg, PreparedView* out) {
  PreparedView& p = *out;
  p.summary.name = view.name;
  if (!seg.ok()) {
    p.why_not = seg.status().message();
    return;
  }
  if (!view.mask_path.empty()) {
    const Result<cv::Mat> given = ReadImageFile(view.mask_path, cv::IMREAD_GRAYSCALE);
    if (!given.ok() || given->size() != p.image.size()) {
      p.why_not = given.ok() ? view.mask_path + ": not the image's size" : given.status().message();
      return;
    }
    seg->label.setTo(kSegHead, (seg->label == kSegHair) & (*given == 0));
    seg->label.setTo(kSegHair, *given != 0);
  }
  p.summary.capture_skin = seg->used_capture_skin;
  p.summary.capture_skin_pixels = seg->capture_skin_pixels;
  const cv::Mat1b hair(seg->label == kSegHair);
  p.summary.hair_pixels = cv::countNonZero(hair);
  if (p.summary.hair_pixels == 0) {
    p.why_not = "no hair is seen";
    return;
  }
  OrientationOptions orientation = options.orientation;
  orientation.threads = 1;
  Result<OrientationMap> map = ComputeOrientationMap(p.image, hair, orientation);
  if (!map.ok()) {
    p.why_not = map.status().message();
    return;
  }
  p.silhouette = SilhouetteOf(*seg, options.hull_uncertain_alpha);
  p.mvs.camera = view.camera;
  p.mvs.cam_from_object = view.cam_from_object;
  cv::Mat grey;
  cv::cvtColor(p.image, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(p.mvs.grey, CV_32F);
  p.mvs.orientation_deg = map->angle_deg.clone();
  p.mvs.orientation_deg.setTo(
      std::numeric_limits<float>::quiet_NaN(),
      map->confidence < static_cast<float>(options.min_orientation_confidence));
  p.mvs.hair = hair & (map->confidence >= static_cast<float>(options.min_orientation_confidence));
  p.summary.stereo_pixels = cv::countNonZero(p.mvs.hair);
  p.summary.median_orientation_confidence = MedianOver(map->confidence, hair);
  p.written = WriteSegmentation(out_dir + "/masks", view.name, *seg);
  if (p.written.ok())
    p.written = WriteOrientation(out_dir + "/orientation", view.name, *map, options.write_pictures);
}

Status WriteDepth(const std::string& dir, const std::string& name, const LineDepthMap& map,
                  bool picture) {
  HR_RETURN_IF_ERROR(
      WriteImageAtomic(dir + "/" + name + "_depth.png", ToUInt16(map.depth_mm, 20.f, 0.f, 0)));
  if (!picture) return Status::Ok();
  const cv::Mat1b valid(map.depth_mm > 0);
  double lo = 0, hi = 0;
  cv::minMaxLoc(map.depth_mm, &lo, &hi, nullptr, nullptr, valid);
  cv::Mat1b scaled;
  map.depth_mm.convertTo(scaled, CV_8U, hi > lo ? 255.0 / (hi - lo) : 1.0,
                         hi > lo ? -lo * 255.0 / (hi - lo) : 0.0);
  cv::Mat coloured;
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_TURBO);
  coloured.setTo(cv::Scalar::all(0), ~valid);
  return WriteImageAtomic(dir + "/" + name + ".jpg", coloured, {cv::IMWRITE_JPEG_QUALITY, 90});
}

// Half-size picture of a view: its hair outline and the points it sees,
// coloured by |direction| (x red, y green, z blue).
cv::Mat ReportPicture(const PreparedView& view, const std::vector<OrientedPoint>& points) {
  cv::Mat shown;
  cv::resize(view.image, shown, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  shown *= 0.6;
  const std::array<double, CameraIntrinsics::kNumParams> params = view.mvs.camera.ToParams();
  for (const OrientedPoint& p : points) {
    if (!std::binary_search(p.views.begin(), p.views.end(), view.input_index)) continue;
    const Eigen::Vector3d q = view.mvs.cam_from_object * p.position_mm.cast<double>();
    if (q.z() <= 1) continue;
    double uv[2];
    ProjectCamPoint(params.data(), q.data(), uv);
    const int x = static_cast<int>(uv[0] * 0.5), y = static_cast<int>(uv[1] * 0.5);
    if (x < 0 || y < 0 || x >= shown.cols || y >= shown.rows) continue;
    const Eigen::Vector3f d = p.direction.cwiseAbs() * 255.f;
    shown.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(d.z()), static_cast<uint8_t>(d.y()),
                                          static_cast<uint8_t>(d.x()));
  }
  cv::Mat1b hair;
  cv::resize(view.mvs.hair, hair, shown.size(), 0, 0, cv::INTER_NEAREST);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(hair, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::drawContours(shown, contours, -1, cv::Scalar(0, 255, 255), 1);
  return shown;
}

Status CreateFolders(const std::string& out_dir) {
  for (const char* sub : {"", "/masks", "/orientation", "/depth", "/report"}) {
    std::error_code ec;
    fs::create_directories(out_dir + sub, ec);
    if (ec) return IoError(out_dir + sub + ": cannot create the folder (" + ec.message() + ")");
  }
  return Status::Ok();
}

void SummariseDepth(const LineDepthMap& map, double max_cost, ViewPointsSummary* s) {
  std::vector<float> costs;
  for (int y = 0; y < map.cost.rows; ++y)
    for (int x = 0; x < map.cost.cols; ++x)
      if (map.depth_mm(y, x) > 0 && map.cost(y, x) <= max_cost) costs.push_back(map.cost(y, x));
  s->depth_cells = static_cast<int>(costs.size());
  s->median_cost = Median(std::move(costs));
}

PointReconstructionOptions WithThreads(PointReconstructionOptions o) {
  o.orientation.threads = o.threads;
  o.hull.threads = o.threads;
  o.mvs.threads = o.threads;
  o.fusion.threads = o.threads;
  return o;
}

}  // namespace

cv::Mat1b SilhouetteOf(const HairSegmentation& segmentation, double uncertain_alpha) {
  const cv::Mat1b& label = segmentation.label;
  cv::Mat1b silhouette(label.size(), kSilhouetteEmpty);
  silhouette.setTo(kSilhouetteSubject, (label == kSegHair) | (label == kSegHead));
  silhouette.setTo(kSilhouetteUnknown, label == kSegBox);
  if (segmentation.hair_alpha.size() == label.size()) {
    silhouette.setTo(kSilhouetteUnknown, (silhouette == kSilhouetteEmpty) &
                                             (segmentation.hair_alpha >= uncertain_alpha));
  }
  return silhouette;
}

Status PointReconstructionOptions::Check() const {
  if (threads < 1) return InvalidArgument("reconstruction threads must be at least 1");
  if (!(min_orientation_confidence >= 0 && min_orientation_confidence < 1))
    return InvalidArgument("reconstruction min_orientation_confidence must be in [0, 1)");
  if (!(hull_uncertain_alpha > 0 && hull_uncertain_alpha <= 1))
    return InvalidArgument("reconstruction hull_uncertain_alpha must be in (0, 1]");
  HR_RETURN_IF_ERROR(segmentation.Check().WithContext("segmentation"));
  HR_RETURN_IF_ERROR(orientation.Check().WithContext("orientation"));
  HR_RETURN_IF_ERROR(hull.Check().WithContext("hull"));
  HR_RETURN_IF_ERROR(mvs.Check().WithContext("mvs"));
  return fusion.Check().WithContext("fusion");
}

nlohmann::json PointReconstructionSummary::ToJson() const {
  nlohmann::json views_json = nlohmann::json::array();
  for (const ViewPointsSummary& v : views) {
    views_json.push_back({{"name", v.name},
                          {"hair_pixels", v.hair_pixels},
                          {"stereo_pixels", v.stereo_pixels},
                          {"capture_skin", v.capture_skin},
                          {"capture_skin_pixels", v.capture_skin_pixels},
                          {"median_orientation_confidence", v.median_orientation_confidence},
                          {"depth_cells", v.depth_cells},
                          {"median_cost", v.median_cost},
                          {"points_seen", v.points_seen}});
  }
  nlohmann::json out = {
      {"format", "hairrig-reconstruction-points"},
      {"version", 1},
      {"object_frame", object_frame},
      {"stride_px", stride_px},
      {"min_orientation_confidence", min_orientation_confidence},
      {"orientation", {{"scales", orientation_scales}, {"smoothing_px", orientation_smoothing_px}}},
      {"points_file", points_file},
      {"views_used", views.size()},
      {"left_out", left_out},
      {"hull", {{"voxels", hull_voxels}, {"voxel_mm", hull_voxel_mm}}},
      {"fusion",
       {{"candidates", fusion.candidates},
        {"consistent", fusion.consistent},
        {"points", fusion.points},
        {"depth_pairs", fusion.depth_pairs},
        {"direction_pairs", fusion.direction_pairs},
        {"depth_confirmed", fusion.depth_confirmed},
        {"mls", fusion.mls},
        {"smoothed_directions", fusion.smoothed_directions}}},
      {"seconds",
       {{"segmentation", segmentation_s},
        {"hull", hull_s},
        {"stereo", stereo_s},
        {"fusion", fusion_s},
        {"writing", writing_s},
        {"total", total_s}}},
      {"views", views_json}};
  if (object_from_box) out["object_from_box"] = PoseToJson(*object_from_box);
  return out;
}

Result<PointReconstructionSummary> ReadPointSummaryFigures(const std::string& path) {
  HR_ASSIGN_OR_RETURN(const nlohmann::json j, ReadJsonFile(path));
  const JsonObject summary(j, path);
  const JsonObject fusion = summary.Object("fusion");
  PointReconstructionSummary s;
  const JsonIntRange counts{.min = 0, .max = int64_t{1} << 50};
  s.fusion.candidates = fusion.Integer("candidates", counts);
  s.fusion.consistent = fusion.Integer("consistent", counts);
  s.fusion.points = fusion.Integer("points", counts);
  s.fusion.depth_pairs = fusion.Integer("depth_pairs", counts);
  s.fusion.direction_pairs = fusion.Integer("direction_pairs", counts);
  s.fusion.depth_confirmed = fusion.Integer("depth_confirmed", counts);
  for (const JsonObject& view : summary.Objects("views")) {
    ViewPointsSummary v;
    v.name = view.String("name");
    v.median_orientation_confidence =
        view.Number("median_orientation_confidence", {.min = 0, .max = 1});
    s.views.push_back(std::move(v));
  }
  if (!summary.ok()) return summary.status();
  return s;
}

std::string PointReconstructionSummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "points: " << fusion.points << " oriented points from " << views.size() << " views ("
    << fusion.consistent << " of " << fusion.candidates
    << " depth cells confirmed by another view), " << object_frame << " frame\n";
  if (fusion.depth_pairs > 0)
    s << "directions: " << fusion.direction_pairs << " of " << fusion.depth_pairs
      << " view pairs that agree on a cell's depth agree on its direction; "
      << fusion.depth_confirmed << " cells at a depth another view confirms\n";
  s << "time: " << total_s << " s (segmentation and orientation " << segmentation_s << " s, hull "
    << hull_s << " s, stereo " << stereo_s << " s, fusion " << fusion_s << " s, writing "
    << writing_s << " s)\n";
  for (const std::string& l : left_out) s << "left out: " << l << "\n";
  s << "wrote: " << points_file << "\n";
  return s.str();
}

Result<PointReconstructionSummary> ReconstructPoints(const ReconstructionInput& input,
                                                     const std::string& out_dir,
                                                     const PointReconstructionOptions& raw_options,
                                                     const ReconstructionProgress& progress) {
  HR_RETURN_IF_ERROR(raw_options.Check());
  const PointReconstructionOptions options = WithThreads(raw_options);
  if (input.views.size() > 65535) return InvalidArgument("reconstruction: at most 65,535 views");
  HR_RETURN_IF_ERROR(CreateFolders(out_dir));
  const auto start = SteadyNowNs();
  PointReconstructionSummary summary;
  summary.object_frame = input.object_frame;
  summary.object_from_box = input.object_from_box;
  summary.stride_px = options.mvs.stride_px;
  summary.min_orientation_confidence = options.min_orientation_confidence;
  summary.orientation_scales = options.orientation.scales;
  summary.orientation_smoothing_px = options.orientation.smoothing_px;
  summary.left_out = input.left_out;

  // Segmentation (the views with too little skin of their own again, with
  // the capture's), then orientation, a view per thread.
  std::vector<PreparedView> prepared(input.views.size());
  std::vector<Result<HairSegmentation>> segmented =
      SegmentCaptureViews(input.views.size(), options.segmentation, options.threads,
                          [&](size_t v, const SkinChromaticity* capture_skin) {
                            return SegmentView(input.views[v], options, capture_skin, &prepared[v]);
                          });
  std::atomic<int> done{0};
  ParallelFor(input.views.size(), options.threads, [&] {
    return [&](size_t v) {
      try {
        PrepareView(input.views[v], options, out_dir, std::move(segmented[v]), &prepared[v]);
      } catch (const std::exception& e) {  // OpenCV's on memory exhaustion, in a worker thread
        prepared[v].why_not = input.views[v].image_path + ": " + e.what();
      }
      prepared[v].input_index = static_cast<uint16_t>(v);
      if (progress) progress("segmentation", ++done, static_cast<int>(input.views.size()));
    };
  });
  std::vector<PreparedView> used;
  for (size_t v = 0; v < prepared.size(); ++v) {
    HR_RETURN_IF_ERROR(prepared[v].written);
    if (prepared[v].why_not.empty()) {
      used.push_back(std::move(prepared[v]));
    } else {
      summary.left_out.push_back(input.views[v].name + ": " + prepared[v].why_not);
    }
  }
  prepared.clear();
  if (used.size() < kMinStereoViews)
    return FailedPrecondition("only " + std::to_string(used.size()) +
                              " view(s) can be used; the stereo needs " +
                              std::to_string(kMinStereoViews));
  summary.segmentation_s = SecondsSince(start);

  // The hull, then each view's depth prior on its stereo pixels.
  auto step = SteadyNowNs();
  std::vector<SilhouetteView> silhouettes;
  for (const PreparedView& p : used)
    silhouettes.push_back({p.mvs.camera, p.mvs.cam_from_object, p.silhouette});
  HR_ASSIGN_OR_RETURN(const VisualHull hull, CarveVisualHull(silhouettes, options.hull));
  silhouettes.clear();
  summary.hull_voxels = hull.OccupiedCount();
  summary.hull_voxel_mm = hull.voxel_mm;
  done = 0;
  ParallelFor(used.size(), options.threads, [&] {
    return [&](size_t v) {
      PreparedView& p = used[v];
      p.mvs.prior_depth_mm = HullDepthMap(hull, p.mvs.camera, p.mvs.cam_from_object, p.mvs.hair,
                                          options.mvs.stride_px);
      if (progress) progress("hull", ++done, static_cast<int>(used.size()));
    };
  });
  summary.hull_s = SecondsSince(step);

  step = SteadyNowNs();
  std::vector<MvsView> mvs_views;
  for (PreparedView& p : used) mvs_views.push_back(p.mvs);
  HR_ASSIGN_OR_RETURN(const std::vector<LineDepthMap> maps,
                      ComputeLineDepthMaps(mvs_views, options.mvs, [&](int d, int total) {
                        if (progress) progress("stereo", d, total);
                      }));
  summary.stereo_s = SecondsSince(step);

  step = SteadyNowNs();
  HR_ASSIGN_OR_RETURN(std::vector<OrientedPoint> points,
                      FusePoints(mvs_views, maps, options.fusion, &summary.fusion));
  for (OrientedPoint& p : points) {
    for (uint16_t& v : p.views) {
      ++used[v].summary.points_seen;
      v = used[v].input_index;
    }
  }
  if (progress) progress("fusion", 1, 1);
  summary.fusion_s = SecondsSince(step);

  step = SteadyNowNs();
  summary.points_file = out_dir + "/points.ply";
  HR_RETURN_IF_ERROR(WritePointCloudPly(summary.points_file, points));
  std::vector<Status> written(used.size());
  done = 0;
  ParallelFor(used.size(), options.threads, [&] {
    return [&](size_t v) {
      written[v] =
          WriteDepth(out_dir + "/depth", used[v].summary.name, maps[v], options.write_pictures);
      if (written[v].ok() && options.write_pictures) {
        written[v] =
            WriteImageAtomic(out_dir + "/report/" + used[v].summary.name + ".jpg",
                             ReportPicture(used[v], points), {cv::IMWRITE_JPEG_QUALITY, 85});
      }
      if (progress) progress("writing", ++done, static_cast<int>(used.size()));
    };
  });
  for (const Status& s : written) HR_RETURN_IF_ERROR(s);
  for (size_t v = 0; v < used.size(); ++v) {
    SummariseDepth(maps[v], options.fusion.max_cost, &used[v].summary);
    summary.views.push_back(used[v].summary);
  }
  summary.writing_s = SecondsSince(step);
  summary.total_s = SecondsSince(start);
  HR_RETURN_IF_ERROR(WriteFileAtomic(out_dir + "/summary.json", summary.ToJson().dump(1)));
  return summary;
}

}  // namespace hairrig
