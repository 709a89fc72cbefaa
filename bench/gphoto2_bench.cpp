// Capture + download through the `gphoto2` backend against the simulated DSLR
// (libgphoto2 -> the project's camlib -> Unix socket -> the camera server):
// the whole trigger-to-downloaded time, and the part libgphoto2, the camlib
// and the transfer take (timed once the camera has written the file, so the
// simulator's rendering is left out). The simulated exposure, readout and
// download times are scaled to nothing (time_scale 1e-4); the lights are on.
// Run from the repository root:
//   build/bench/hairrig_gphoto2_bench [shots]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "core/statistics.h"
#include "drivers/gphoto2_camera.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"

namespace hairrig {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

int Run(int shots) {
  auto scene = LoadScene("etc/scenes/default.yaml");
  if (!scene.ok()) {
    std::fprintf(stderr, "%s\n", scene.status().ToString().c_str());
    return 1;
  }
  SimWorldOptions world_options;
  world_options.time_scale = 1e-4;
  auto world = CreateSimWorld(*scene, world_options).value();
  for (const SceneLight& l : scene->lights) {
    if (!SetWorldLightLevel(*world, l.name, 1.0).ok()) return 1;
  }
  if (Status s = ExportSimDslrCamlibs(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 1;
  }
  SimDslrOptions server_options;
  server_options.serial = scene->cameras[0].serial;
  auto server = SimDslrServer::Start(world, server_options).value();
  Gphoto2CameraOptions o;
  o.port = server->port();
  o.model = sim_dslr::kModel;
  o.nominal.time_scale = 1e-4;
  auto camera = MakeGphoto2Camera(
      {DeviceKind::kCamera, "bench", "gphoto2", server_options.serial, "bench"}, o);
  const auto open_start = Clock::now();
  if (Status s = camera->Open(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 1;
  }
  const double open_s = SecondsSince(open_start);
  if (!camera->Configure({}).ok() || !camera->Arm().ok()) return 1;

  std::vector<double> capture_s, transfer_s;
  size_t bytes = 0;
  for (int i = 0; i < 2 * shots; ++i) {
    const bool whole = i % 2 == 0;  // alternate: whole shot, then transfer only
    const int written = server->shots();
    auto t0 = Clock::now();
    if (!camera->SoftwareTrigger().ok()) return 1;
    if (!whole) {
      while (server->shots() == written) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      t0 = Clock::now();
    }
    auto frame = camera->WaitFrame(std::chrono::seconds(30));
    if (!frame.ok()) {
      std::fprintf(stderr, "%s\n", frame.status().ToString().c_str());
      return 1;
    }
    (whole ? capture_s : transfer_s).push_back(SecondsSince(t0));
    bytes = frame->data.size();
  }
  const double capture = Median(capture_s), transfer = Median(transfer_s);
  std::printf("# gphoto2 backend against the simulated DSLR, %d shots, %dx%d JPEG of %.1f MB\n",
              shots, scene->cameras[0].intrinsics.width_px, scene->cameras[0].intrinsics.height_px,
              static_cast<double>(bytes) / 1e6);
  std::printf("open (load camlibs, connect, read serial)   %8.1f ms\n", open_s * 1e3);
  std::printf("trigger -> file downloaded (median)         %8.1f ms\n", capture * 1e3);
  std::printf("  of which event + download + delete        %8.1f ms (%.0f MB/s)\n", transfer * 1e3,
              static_cast<double>(bytes) / 1e6 / transfer);
  std::printf("  the rest: the simulator renders and encodes the view\n");
  return 0;
}

}  // namespace
}  // namespace hairrig

int main(int argc, char** argv) {
  return hairrig::Run(argc > 1 ? std::max(3, std::atoi(argv[1])) : 15);
}
