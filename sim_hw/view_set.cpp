#include "sim_hw/view_set.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/contact_sheet.h"
#include "core/file_util.h"
#include "core/strand_io.h"
#include "sim_hw/ground_truth.h"

namespace hairrig {

std::string ViewFileName(int view, const std::string& serial) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%03d", view);
  return std::string(buf) + "_" + serial + ".png";
}

Result<RenderViewsSummary> RenderAllViews(const Renderer& renderer, const std::string& out_dir,
                                          const RenderViewsOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene& scene = renderer.scene();
  const int n = NumViews(scene);
  std::vector<cv::Mat> images(static_cast<size_t>(n));
  std::vector<ViewGroundTruth> truths(static_cast<size_t>(n));
  std::vector<Status> errors(static_cast<size_t>(n));
  std::atomic<int> next{0};
  const auto work = [&] {
    for (int v = next++; v < n; v = next++) {
      ViewGroundTruth g = MakeViewGroundTruth(scene, v);
      RenderOptions o;
      o.noise = options.noise;
      o.noise_seed = scene.seed * 1000003ull + static_cast<uint64_t>(v);
      o.light_levels = options.light_levels;
      o.threads = 1;  // the views are already spread over the threads
      o.ground_truth = true;
      auto view = renderer.Render(g.camera_index, g.turntable_deg, o);
      if (!view.ok()) {
        errors[static_cast<size_t>(v)] = view.status();
        continue;
      }
      g.tags = view->tags;
      const std::string path = out_dir + "/" + ViewFileName(v, g.camera_serial);
      std::vector<uint8_t> png;
      if (!cv::imencode(".png", view->image, png)) {
        errors[static_cast<size_t>(v)] = IoError(path + ": PNG encoding failed");
        continue;
      }
      errors[static_cast<size_t>(v)] = WriteFileAtomic(path, png.data(), png.size());
      if (errors[static_cast<size_t>(v)].ok()) {
        errors[static_cast<size_t>(v)] = WriteViewTruthMaps(out_dir + "/views", v, view->truth);
      }
      images[static_cast<size_t>(v)] = view->image;
      truths[static_cast<size_t>(v)] = std::move(g);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < std::max(1, options.threads); ++t) pool.emplace_back(work);
  for (auto& t : pool) t.join();
  for (const Status& s : errors) HR_RETURN_IF_ERROR(s);

  RenderViewsSummary summary;
  summary.views = n;
  std::vector<std::string> labels;
  for (const ViewGroundTruth& g : truths) {
    summary.files.push_back(ViewFileName(g.view, g.camera_serial));
    char label[96];
    std::snprintf(label, sizeof(label), "%d %s %.1f deg", g.view, g.camera_serial.c_str(), g.turntable_deg);
    labels.emplace_back(label);
  }
  const int columns = static_cast<int>(scene.cameras.size()) * 4;
  std::vector<uint8_t> png;
  cv::imencode(".png", MakeContactSheet(images, labels, columns, 240), png);
  summary.contact_sheet = "contact_sheet.png";
  HR_RETURN_IF_ERROR(WriteFileAtomic(out_dir + "/" + summary.contact_sheet, png.data(), png.size()));
  HR_RETURN_IF_ERROR(WriteTruthHeadMesh(scene, out_dir));
  summary.ground_truth = "ground_truth.json";
  HR_RETURN_IF_ERROR(WriteFileAtomic(out_dir + "/" + summary.ground_truth, GroundTruthJson(scene, truths, /*with_maps=*/true)));
  HR_RETURN_IF_ERROR(WriteStrands(out_dir + "/ground_truth_strands.ply", renderer.strands_turntable_mm()));
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace hairrig
