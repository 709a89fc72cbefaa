#include "rig/reconstruct_capture.h"

#include <algorithm>
#include <future>
#include <nlohmann/json.hpp>

#include "core/file_util.h"
#include "core/head_model.h"
#include "core/image_file.h"
#include "core/log.h"
#include "core/strand_io.h"
#include "core/string_format.h"
#include "reconstruction/colmap_model.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/skin_views.h"
#include "reconstruction/strand_preview.h"
#include "rig/gltf_export.h"
#include "rig/reconstruction_input.h"

namespace hairrig {

namespace {

Result<ReconstructionInput> LoadInput(const ReconstructCaptureOptions& o) {
  ReconstructionInput input;
  if (!o.colmap_dir.empty()) {
    ColmapReadOptions colmap;
    colmap.images_dir = o.images_dir;
    colmap.masks_dir = o.masks_dir;
    HR_ASSIGN_OR_RETURN(input, ReadColmapModel(o.colmap_dir, colmap));
  } else {
    HR_ASSIGN_OR_RETURN(input, LoadCaptureReconstructionInput(o.dir));
  }
  HR_RETURN_IF_ERROR(SelectViews(o.views, &input));
  return input;
}

// Four views evenly spread through the list (a turntable capture lists them by angle).
std::vector<ReconstructionView> SpreadViews(const std::vector<ReconstructionView>& views,
                                            size_t count) {
  std::vector<ReconstructionView> chosen;
  const size_t n = std::min(count, views.size());
  for (size_t i = 0; i < n; ++i) chosen.push_back(views[i * views.size() / n]);
  return chosen;
}

Result<std::string> WriteOverViews(const ReconstructionInput& input, const StrandSet& strands,
                                   const std::string& strands_dir) {
  HR_ASSIGN_OR_RETURN(
      const cv::Mat picture,
      RenderStrandsOverViews(SpreadViews(input.views, 4), strands, StrandOverlayOptions{}));
  if (picture.empty()) return std::string();
  const std::string path = strands_dir + "/over_views.jpg";
  HR_RETURN_IF_ERROR(WriteImageAtomic(path, picture));
  return path;
}

// The strands' over-views picture and plausibility (reconstruction_verdict.h),
// from the strands and points as written.
Status CheckStrands(const ReconstructionInput& input, const SkinViews* skin,
                    const StrandSet& strands, const std::vector<OrientedPoint>& points,
                    ReconstructCaptureSummary* summary) {
  HR_ASSIGN_OR_RETURN(summary->over_views_picture,
                      WriteOverViews(input, strands, summary->strands->output_dir));
  HR_ASSIGN_OR_RETURN(summary->plausibility, MeasureStrandPlausibility(strands, points, skin));
  return Status::Ok();
}

Status RunStrands(const ReconstructCaptureOptions& o, const ReconstructionInput& input,
                  ReconstructCaptureSummary* summary) {
  SubjectHeadRequest request;
  request.head_file = o.head_file;
  request.capture_dir = o.colmap_dir.empty() ? o.dir : "";
  request.reconstruction_dir = o.dir + "/reconstruction";
  request.views = &input.views;
  request.threads = o.strands.threads;
  HR_ASSIGN_OR_RETURN(const SubjectHead head, ResolveSubjectHead(request));
  summary->head_fit = head.fit;
  LogInfo("reconstruct: strands (" + std::string(StrandMethodName(o.strands.method)) + ") from " +
          o.dir + "/reconstruction/points.ply, head " + head.source);
  // The views' skin (the points stage's label masks): strands end in front of
  // it, and the plausibility counts the strand samples over it.
  // The scalp that shows between the hair is not bare skin (SkinViews::ExcludeScalp).
  HR_ASSIGN_OR_RETURN(const std::unique_ptr<HeadModel> head_model, HeadModel::Build(head.spec));
  Result<SkinViews> skin = SkinViews::Load(input.views, request.reconstruction_dir + "/masks",
                                           head.spec.center_turntable_mm);
  if (skin.ok()) skin->ExcludeScalp(head_model.get(), kScalpSkinBandMm);
  if (!skin.ok() && o.strands.growth.end_over_skin) {
    LogWarning("reconstruct: strands are not stopped in front of skin: " +
               skin.status().ToString());
  }
  const SkinViews* skin_views = skin.ok() ? &*skin : nullptr;
  HR_ASSIGN_OR_RETURN(summary->strands,
                      ReconstructStrands(request.reconstruction_dir, head.spec, head.source,
                                         o.strands, skin_views, &input.views));
  // The strands and points as written, read once for the checks and the display copy.
  HR_ASSIGN_OR_RETURN(const StrandSet strands,
                      ReadStrands(summary->strands->output_dir + "/strands.ply"));
  HR_ASSIGN_OR_RETURN(const std::vector<OrientedPoint> points,
                      ReadPointCloudPly(request.reconstruction_dir + "/points.ply"));
  // The display copy as glTF, for the console's 3D view and for download,
  // written on a second thread while the checks run: the two share only const
  // inputs and each writes its own file; only the checks write *summary. The
  // checks' error is reported before the export's.
  GltfExportOptions gltf;
  gltf.dir = o.dir;
  gltf.head_file = o.head_file == kFittedHead ? "" : o.head_file;
  gltf.display_only = true;
  std::future<Result<GltfExportSummary>> display = std::async(std::launch::async, [&] {
    return ExportCaptureGltf(gltf, {.strands = &strands, .points = &points});
  });
  const Status checked = CheckStrands(input, skin_views, strands, points, summary);
  const Result<GltfExportSummary> exported = display.get();
  HR_RETURN_IF_ERROR(checked);
  HR_RETURN_IF_ERROR(exported.status());
  summary->display_glb = exported->display.path;
  return Status::Ok();
}

// The verdict on the stages' figures; a run of the strands stage alone
// judges the points from the points stage's summary.json.
void Judge(const std::string& reconstruction_dir, ReconstructCaptureSummary* summary) {
  std::optional<PointReconstructionSummary> points = summary->points;
  Status points_read;
  if (!points) {
    Result<PointReconstructionSummary> read =
        ReadPointSummaryFigures(reconstruction_dir + "/summary.json");
    if (read.ok()) points = *read;
    points_read = read.status();
  }
  summary->verdict = JudgeReconstruction(points ? &*points : nullptr,
                                         summary->plausibility ? &*summary->plausibility : nullptr);
  if (points_read.ok()) return;
  summary->verdict.level = std::max(summary->verdict.level, ReconstructionVerdict::Level::kCheck);
  summary->verdict.reasons.push_back("the points were not judged: " + points_read.ToString() +
                                     "; run `hairrig reconstruct DIR --stage points` again");
}

}  // namespace

Result<ReconstructStage> ParseReconstructStage(const std::string& name) {
  if (name == "points") return ReconstructStage::kPoints;
  if (name == "strands") return ReconstructStage::kStrands;
  if (name == "all") return ReconstructStage::kAll;
  return InvalidArgument("reconstruct stage '" + name + "' is not one of points, strands, all");
}

Status ReconstructCaptureOptions::Check() const {
  if (dir.empty()) return InvalidArgument("reconstruct: the capture folder is required");
  if (!colmap_dir.empty() && images_dir.empty()) {
    return InvalidArgument("--colmap needs --images (the folder the model's image names are in)");
  }
  if (!colmap_dir.empty() && stage != ReconstructStage::kPoints)
    HR_RETURN_IF_ERROR(CheckColmapHead(head_file));
  if (stage != ReconstructStage::kStrands) HR_RETURN_IF_ERROR(points.Check().WithContext("points"));
  if (stage != ReconstructStage::kPoints)
    HR_RETURN_IF_ERROR(strands.Check().WithContext("strands"));
  return Status::Ok();
}

nlohmann::json ReconstructCaptureSummary::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  if (points) j["points"] = points->ToJson();
  if (head_fit) j["head_fit"] = head_fit->ToJson();
  if (strands) j["strands"] = strands->ToJson();
  if (plausibility) j["plausibility"] = plausibility->ToJson();
  j["verdict"] = verdict.name();
  j["reasons"] = verdict.reasons;
  j["views_to_check"] = verdict.views_to_check;
  if (!over_views_picture.empty()) j["over_views_picture"] = over_views_picture;
  if (!display_glb.empty()) j["display_glb"] = display_glb;
  j["brief"] = BriefReport();
  return j;
}

std::string ReconstructCaptureSummary::BriefReport() const {
  std::string brief = std::string("verdict: ") + verdict.name() + "\n";
  for (const std::string& reason : verdict.reasons) brief += "  - " + reason + "\n";
  brief += (points ? points->BriefReport() : "") + (head_fit ? head_fit->BriefReport() : "") +
           (strands ? strands->BriefReport() : "");
  if (plausibility) {
    brief += StringPrintf(
        "  strands' median length %.0f mm, the hair spans %.0f mm; %.2f %% of the samples facing "
        "a camera lie over skin (%d views)\n",
        plausibility->median_length_mm, plausibility->hair_extent_mm,
        100 * plausibility->over_skin_share(), plausibility->views_measured);
  }
  if (!over_views_picture.empty())
    brief += "  strands over the input views: " + over_views_picture + "\n";
  if (!display_glb.empty()) brief += "  for display and download (glTF): " + display_glb + "\n";
  return brief;
}

Result<ReconstructCaptureSummary> ReconstructCapture(const ReconstructCaptureOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  HR_ASSIGN_OR_RETURN(const ReconstructionInput input, LoadInput(o));
  ReconstructCaptureSummary summary;
  if (o.stage != ReconstructStage::kStrands) {
    HR_ASSIGN_OR_RETURN(summary.points,
                        ReconstructPoints(input, o.dir + "/reconstruction", o.points, o.progress));
  }
  if (o.stage != ReconstructStage::kPoints) {
    HR_RETURN_IF_ERROR(RunStrands(o, input, &summary));
  }
  Judge(o.dir + "/reconstruction", &summary);
  HR_RETURN_IF_ERROR(
      WriteFileAtomic(o.dir + "/reconstruction/verdict.json", summary.verdict.ToJson().dump(1)));
  return summary;
}

}  // namespace hairrig
