// Frames per second through the `aravis` backend at the default camera
// resolution (1200 x 1600), software-triggered one after the other:
//   - over GigE Vision on 127.0.0.1 with Aravis' own test pattern, which
//     times the transport alone (GVCP trigger, GVSP packets, reassembly),
//     with the stream's missing and resent packets;
//   - with the rendered world (in-process fake and GigE), which the
//     simulator's rendering bounds.
// Uses 127.0.0.1:3956: do not run beside `hairrig sim serve` or the tests.
// Run from the repository root:
//   build/bench/hairrig_aravis_bench [frames]
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "drivers/aravis_camera.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {
namespace {

using Clock = std::chrono::steady_clock;

struct Run {
  double fps = 0;
  AravisStreamStats stats;
  bool ok = false;
};

Run Measure(Camera& camera, PixelFormat format, int frames) {
  Run run;
  if (Status s = camera.Open(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return run;
  }
  CaptureSettings settings;
  settings.format = format;
  settings.exposure_s = 0.001;
  if (!camera.Configure(settings).ok() || !camera.Arm().ok()) return run;
  const auto t0 = Clock::now();
  for (int i = 0; i < frames; ++i) {
    auto frame = camera.SoftwareTrigger().ok() ? camera.WaitFrame(std::chrono::seconds(30))
                                               : Result<Frame>(Internal("trigger failed"));
    if (!frame.ok()) {
      std::fprintf(stderr, "%s\n", frame.status().ToString().c_str());
      return run;
    }
  }
  run.fps = frames / std::chrono::duration<double>(Clock::now() - t0).count();
  run.stats = AravisCameraStreamStats(camera);
  run.ok = camera.Disarm().ok() && camera.Close().ok();
  return run;
}

void Print(const char* what, const Run& r) {
  std::printf(
      "%-44s %7.1f fps   completed %lu  failures %lu  underruns %lu  missing packets %lu  resent "
      "%lu\n",
      what, r.fps, static_cast<unsigned long>(r.stats.completed),
      static_cast<unsigned long>(r.stats.failures), static_cast<unsigned long>(r.stats.underruns),
      static_cast<unsigned long>(r.stats.missing_packets),
      static_cast<unsigned long>(r.stats.resent_packets));
}

int Main(int frames) {
  auto scene = LoadScene("etc/scenes/default.yaml");
  if (!scene.ok()) return 1;
  SimWorldOptions world_options;
  world_options.time_scale = 1e-4;
  auto world = CreateSimWorld(*scene, world_options).value();
  for (const SceneLight& l : scene->lights) {
    if (!SetWorldLightLevel(*world, l.name, 1.0).ok()) return 1;
  }
  const std::string serial = scene->cameras[1].serial;
  AravisCameraOptions o;
  o.nominal.width_px = scene->cameras[1].intrinsics.width_px;
  o.nominal.height_px = scene->cameras[1].intrinsics.height_px;
  std::printf("# aravis backend, %dx%d, %d software-triggered frames each\n", o.nominal.width_px,
              o.nominal.height_px, frames);
  const DeviceInfo info{DeviceKind::kCamera, "bench", "aravis", serial, "bench"};
  {
    auto gige = SimGigECamera::Start(world, {serial, 1, "", /*render=*/false});
    if (!gige.ok()) return 1;
    o.address = (*gige)->address();
    for (PixelFormat f : {PixelFormat::kMono8, PixelFormat::kRgb8}) {
      auto camera = MakeAravisCamera(info, o);
      const std::string what = std::string("GigE loopback, test pattern, ") + PixelFormatName(f);
      Print(what.c_str(), Measure(*camera, f, frames));
    }
  }
  {
    auto gige = SimGigECamera::Start(world, {serial, 1, "", true});
    if (!gige.ok()) return 1;
    auto camera = MakeAravisCamera(info, o);
    Print("GigE loopback, rendered view, RGB8", Measure(*camera, PixelFormat::kRgb8, frames));
  }
  const SimAravisOptions feed_options{serial, 1, "", true};
  SimAravisFeed feed(world, feed_options);
  o.address.clear();
  o.connect = [&feed, feed_options]() { return OpenSimAravisCamera(feed, feed_options); };
  auto camera = MakeAravisCamera(info, o);
  Print("in-process fake, rendered view, RGB8", Measure(*camera, PixelFormat::kRgb8, frames));
  return 0;
}

}  // namespace
}  // namespace hairrig

int main(int argc, char** argv) {
  return hairrig::Main(argc > 1 ? std::max(2, std::atoi(argv[1])) : 20);
}
