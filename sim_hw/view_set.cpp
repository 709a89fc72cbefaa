#include "sim_hw/view_set.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/contact_sheet.h"
#include "core/file_util.h"
#include "core/image_file.h"
#include "core/parallel.h"
#include "core/strand_io.h"
#include "core/string_format.h"
#include "sim_hw/ground_truth.h"

namespace hairrig {

std::string ViewFileName(int view, const std::string& serial) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%03d", view);
  return std::string(buf) + "_" + serial + ".png";
}

Status RenderViewsOptions::Check() const {
  if (threads < 1)
    return InvalidArgument("threads must be at least 1, got " + std::to_string(threads));
  for (size_t i = 0; i < light_levels.size(); ++i) {
    if (!(light_levels[i] >= 0 && light_levels[i] <= 1))
      return InvalidArgument("light_levels[" + std::to_string(i) + "] must lie in 0..1");
  }
  return Status::Ok();
}

Result<RenderViewsSummary> RenderAllViews(const Renderer& renderer, const std::string& out_dir,
                                          const RenderViewsOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("render views"));
  const auto t0 = std::chrono::steady_clock::now();
  const Scene& scene = renderer.scene();
  const int n = NumViews(scene);
  std::vector<cv::Mat> images(static_cast<size_t>(n));
  std::vector<ViewGroundTruth> truths(static_cast<size_t>(n));
  std::vector<Status> errors(static_cast<size_t>(n));
  ParallelFor(static_cast<size_t>(n), options.threads, [&] {
    return [&](size_t v) {
      ViewGroundTruth g = MakeViewGroundTruth(scene, static_cast<int>(v));
      RenderOptions o;
      o.noise = options.noise;
      o.noise_seed = scene.seed * 1000003ull + v;
      o.light_levels = options.light_levels;
      o.threads = 1;  // the views are already spread over the threads
      o.ground_truth = true;
      auto view = renderer.Render(g.camera_index, g.turntable_deg, o);
      if (!view.ok()) {
        errors[v] = view.status();
        return;
      }
      g.tags = view->tags;
      const std::string path = out_dir + "/" + ViewFileName(static_cast<int>(v), g.camera_serial);
      errors[v] = WriteImageAtomic(path, view->image);
      if (errors[v].ok())
        errors[v] = WriteViewTruthMaps(out_dir + "/views", static_cast<int>(v), view->truth);
      images[v] = view->image;
      truths[v] = std::move(g);
    };
  });
  for (const Status& s : errors) HR_RETURN_IF_ERROR(s);

  RenderViewsSummary summary;
  summary.views = n;
  std::vector<std::string> labels;
  for (const ViewGroundTruth& g : truths) {
    summary.files.push_back(ViewFileName(g.view, g.camera_serial));
    char label[96];
    std::snprintf(label, sizeof(label), "%d %s %.1f deg", g.view, g.camera_serial.c_str(),
                  g.turntable_deg);
    labels.emplace_back(label);
  }
  const int columns = static_cast<int>(scene.cameras.size()) * 4;
  summary.contact_sheet = "contact_sheet.png";
  HR_RETURN_IF_ERROR(WriteImageAtomic(out_dir + "/" + summary.contact_sheet,
                                      MakeContactSheet(images, labels, columns, 240)));
  HR_RETURN_IF_ERROR(WriteTruthHeadMesh(scene, out_dir));
  summary.ground_truth = "ground_truth.json";
  HR_RETURN_IF_ERROR(WriteFileAtomic(out_dir + "/" + summary.ground_truth,
                                     GroundTruthJson(scene, truths, /*with_maps=*/true)));
  HR_RETURN_IF_ERROR(
      WriteStrands(out_dir + "/ground_truth_strands.ply", renderer.strands_turntable_mm()));
  HR_ASSIGN_OR_RETURN(const auto sums, HashTruthFolder(out_dir));
  HR_RETURN_IF_ERROR(WriteTruthChecksums(out_dir, sums));
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

namespace {

Result<std::unique_ptr<Renderer>> LoadRenderer(const std::string& scene_file) {
  HR_ASSIGN_OR_RETURN(const Scene scene, LoadScene(scene_file));
  return Renderer::Create(scene);
}

std::string CropText(const cv::Rect& r) {
  return std::to_string(r.x) + "," + std::to_string(r.y) + "," + std::to_string(r.width) + "," +
         std::to_string(r.height);
}

}  // namespace

Status RenderSceneViewsOptions::Check() const {
  if (scene_file.empty()) return InvalidArgument("sim render: scene_file is required");
  if (out_dir.empty())
    return InvalidArgument("sim render: out_dir (--out, the output folder) is required");
  return render.Check().WithContext("sim render: render");
}

nlohmann::json RenderSceneViewsSummary::ToJson() const {
  return {{"views", views.views},
          {"out", out_dir},
          {"contact_sheet", out_dir + "/" + views.contact_sheet},
          {"ground_truth", out_dir + "/" + views.ground_truth},
          {"strands", strands},
          {"wall_s", views.wall_s},
          {"seconds_per_view", views.wall_s / std::max(1, views.views)}};
}

std::string RenderSceneViewsSummary::BriefReport() const {
  return StringPrintf(
      "rendered %d views in %.1f s (%.2f s per view) to %s\ncontact sheet: %s\nground truth: %s\n",
      views.views, views.wall_s, views.wall_s / std::max(1, views.views), out_dir.c_str(),
      (out_dir + "/" + views.contact_sheet).c_str(), (out_dir + "/" + views.ground_truth).c_str());
}

Result<RenderSceneViewsSummary> RenderSceneViews(const RenderSceneViewsOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const std::unique_ptr<Renderer> renderer, LoadRenderer(options.scene_file));
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec)
    return IoError(options.out_dir + ": cannot create the output folder (" + ec.message() + ")");
  RenderSceneViewsSummary summary;
  summary.out_dir = options.out_dir;
  HR_ASSIGN_OR_RETURN(summary.views, RenderAllViews(*renderer, options.out_dir, options.render));
  summary.strands = renderer->strands_turntable_mm().num_strands();
  return summary;
}

Status RenderViewFileOptions::Check() const {
  if (scene_file.empty()) return InvalidArgument("sim render: scene_file is required");
  if (view < 0) return InvalidArgument("--view " + std::to_string(view) + " must be 0 or more");
  if (crop_px && (crop_px->width <= 0 || crop_px->height <= 0))
    return InvalidArgument("--crop " + CropText(*crop_px) +
                           " must have a positive width and height");
  const std::string ext = FileExtension(out_file);
  if (ext != "png" && ext != "tif" && ext != "tiff" && ext != "jpg") {
    return InvalidArgument("--out " + out_file +
                           ": give an image file name ending in .png, .tif or .jpg");
  }
  return Status::Ok();
}

nlohmann::json RenderViewFileSummary::ToJson() const {
  return {{"view", view},
          {"camera_serial", camera_serial},
          {"turntable_deg", turntable_deg},
          {"out", out_file},
          {"width_px", width_px},
          {"height_px", height_px},
          {"tags_unoccluded", tags_unoccluded}};
}

std::string RenderViewFileSummary::BriefReport() const {
  return StringPrintf("view %d (%s, turntable %.2f deg) -> %s\n", view, camera_serial.c_str(),
                      turntable_deg, out_file.c_str());
}

Result<RenderViewFileSummary> RenderViewFile(const RenderViewFileOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const std::unique_ptr<Renderer> renderer, LoadRenderer(options.scene_file));
  const Scene& scene = renderer->scene();
  const int n = NumViews(scene);
  if (options.view < 0 || options.view >= n) {
    return InvalidArgument("--view " + std::to_string(options.view) +
                           " is outside the plan's views 0-" + std::to_string(n - 1));
  }
  const ViewGroundTruth g = MakeViewGroundTruth(scene, options.view);
  RenderOptions render;
  render.noise = options.noise;
  render.noise_seed = scene.seed * 1000003ull + static_cast<uint64_t>(options.view);
  HR_ASSIGN_OR_RETURN(RenderedView view, renderer->Render(g.camera_index, g.turntable_deg, render));
  if (options.crop_px) {
    const cv::Rect& rect = *options.crop_px;
    if (rect.width <= 0 || rect.height <= 0 ||
        (rect & cv::Rect(0, 0, view.image.cols, view.image.rows)) != rect) {
      return InvalidArgument("--crop " + CropText(rect) + " is not inside the " +
                             std::to_string(view.image.cols) + " x " +
                             std::to_string(view.image.rows) + " view");
    }
    view.image = view.image(rect).clone();
  }
  HR_RETURN_IF_ERROR(WriteImageAtomic(options.out_file, view.image));
  RenderViewFileSummary summary{options.view,
                                g.camera_serial,
                                g.turntable_deg,
                                options.out_file,
                                view.image.cols,
                                view.image.rows,
                                0};
  for (const TagTruth& t : view.tags) summary.tags_unoccluded += t.unoccluded ? 1 : 0;
  return summary;
}

}  // namespace hairrig
