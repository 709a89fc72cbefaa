// Capture benchmarks (run from the repository root):
//   build/bench/hairrig_capture_bench [efficiency] [ingest]
// efficiency: the default plan on the default simulated rig (full-size frames,
//   hair drawn) at realistic timings (time_scale 1, then 0.5): wall time of the
//   sweep against its physical lower bound (moves + settles + exposures + the
//   last download).
// ingest: frames checked, encoded, hashed, written atomically and journalled
//   per second (CaptureDataset::StoreFrame), raw and pass-through, and SHA-256
//   alone, on one rendered 1200x1600 view.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <string>

#include "core/sha256.h"
#include "rig/capture.h"
#include "rig/capture_dataset.h"
#include "rig/rig_config.h"
#include "sim_hw/renderer.h"
#include "sim_rig/sim_rig.h"

namespace fs = std::filesystem;
using namespace hairrig;
using Clock = std::chrono::steady_clock;

namespace {

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hairrig_bench_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

int Efficiency() {
  std::printf(
      "# capture efficiency, default plan on the default simulated rig (etc/sim-rig.yaml)\n");
  std::printf("%-11s %8s %10s %14s %11s\n", "time_scale", "views", "wall_s", "lower_bound_s",
              "efficiency");
  std::ifstream in("etc/sim-rig.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  for (double scale : {1.0, 0.5}) {
    const std::string dir = TempDir("efficiency");
    std::string config = std::regex_replace(text, std::regex("time_scale: [0-9.]+"),
                                            "time_scale: " + std::to_string(scale));
    config = std::regex_replace(config, std::regex("scene: scenes/"),
                                "scene: " + fs::absolute("etc/scenes").string() + "/");
    std::ofstream(dir + "/rig.yaml") << config;
    CaptureOptions o;
    o.config_path = dir + "/rig.yaml";
    o.out_dir = dir + "/capture";
    auto s = RunCapture(o);
    if (!s.ok() || s->status != "complete") {
      std::fprintf(stderr, "capture failed: %s\n",
                   s.ok() ? s->message.c_str() : s.status().ToString().c_str());
      return 1;
    }
    std::printf("%-11.2f %8d %10.3f %14.3f %11.3f\n", scale, s->views_completed, s->wall_s,
                s->lower_bound_s, s->efficiency);
    fs::remove_all(dir);
  }
  return 0;
}

int Ingest() {
  auto scene = LoadScene("etc/scenes/default.yaml");
  if (!scene.ok()) return 1;
  auto renderer = Renderer::Create(*scene);
  if (!renderer.ok()) return 1;
  RenderOptions ro;
  ro.light_levels = {1.0, 1.0};
  auto view = (*renderer)->Render(0, 0.0, ro);
  if (!view.ok()) return 1;
  cv::Mat rgb;
  cv::cvtColor(view->image, rgb, cv::COLOR_BGR2RGB);
  Frame raw;
  raw.camera_serial = "BENCH";
  raw.width_px = rgb.cols;
  raw.height_px = rgb.rows;
  raw.format = PixelFormat::kRgb8;
  raw.data.assign(rgb.datastart, rgb.dataend);
  Frame encoded = raw;
  encoded.format = PixelFormat::kEncoded;
  encoded.encoding = "png";
  cv::imencode(".png", view->image, encoded.data, {cv::IMWRITE_PNG_COMPRESSION, 1});

  std::printf(
      "# ingest: CaptureDataset::StoreFrame, 1200x1600 RGB rendered view, %d frames per row\n", 38);
  std::printf("%-34s %9s %12s %13s\n", "path", "frames/s", "raw MB/s", "stored MB/s");
  for (const auto& [name, frame, compression] :
       {std::tuple{"raw RGB8 -> PNG level 1", &raw, 1},
        std::tuple{"raw RGB8 -> PNG level 0", &raw, 0},
        std::tuple{"encoded PNG pass-through (replay)", &encoded, 1}}) {
    const std::string dir = TempDir("ingest");
    auto dataset =
        CaptureDataset::Create(dir + "/c", "bench: true\n", {}, {.png_compression = compression});
    if (!dataset.ok()) return 1;
    std::vector<PlannedViewRecord> plan;
    for (int v = 0; v < 38; ++v) plan.push_back({v, v / 2, 0, "bench", frame->camera_serial, {}});
    if (!(*dataset)->JournalPlan(plan).ok()) return 1;
    const auto t0 = Clock::now();
    uint64_t stored = 0;
    for (int v = 0; v < 38; ++v) {
      FrameContext context{v, v / 2, "bench", 0, 0, 1200, 1600};
      auto info = (*dataset)->StoreFrame(*frame, context);
      if (!info.ok()) {
        std::fprintf(stderr, "%s\n", info.status().ToString().c_str());
        return 1;
      }
      stored += info->record.bytes;
    }
    const double s = Seconds(t0);
    const double raw_mb = static_cast<double>(raw.data.size()) / 1e6;
    std::printf("%-34s %9.1f %12.1f %13.1f\n", name, 38 / s, 38 * raw_mb / s,
                static_cast<double>(stored) / 1e6 / s);
    fs::remove_all(dir);
  }
  const auto t0 = Clock::now();
  for (int i = 0; i < 10; ++i) (void)Sha256Hex(raw.data.data(), raw.data.size());
  std::printf("%-34s %9s %12.1f\n", "SHA-256 alone", "",
              10 * static_cast<double>(raw.data.size()) / 1e6 / Seconds(t0));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  RegisterSimRig();  // the captures are the simulated rig's
  bool efficiency = argc == 1, ingest = argc == 1;
  for (int i = 1; i < argc; ++i) {
    efficiency = efficiency || std::string(argv[i]) == "efficiency";
    ingest = ingest || std::string(argv[i]) == "ingest";
  }
  int rc = 0;
  if (ingest) rc |= Ingest();
  if (efficiency) rc |= Efficiency();
  return rc;
}
