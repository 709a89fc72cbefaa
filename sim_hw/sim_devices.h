// The in-process `sim` backend: turntable, LED panels, trigger lines and
// cameras behind the drivers/ interfaces, sharing one SimWorld whose renderer
// draws each frame at the turntable angle and light state of its trigger.
//
// Timings are the scene's realistic ones (turntable speed, acceleration and
// settle; camera exposure, readout and download) multiplied by `time_scale`
// (1 = real time; 0.01 = a hundred times faster), so tests run fast and
// capture efficiency can still be measured against the physical lower bound.
//
// Backend fields in the rig config (devices section):
//   lights:        light: <scene light name>   (default: the device name)
//   trigger_lines: (none)
//   cameras:       trigger_line: <line name>   (optional; cameras on one line
//                  expose together on Pulse())
//   input_lines:   (none; all simulated input lines go active on an `estop` fault)
//
// Faults (sim_hw/sim_faults.h) are injected through `SimWorldOptions::faults`.
#pragma once

#include <functional>
#include <memory>

#include "core/capture_storage.h"
#include "drivers/registry.h"
#include "drivers/trigger_bus.h"
#include "sim_hw/renderer.h"
#include "sim_hw/sim_faults.h"

namespace hairrig {

class SimWorld;

struct SimWorldOptions {
  double time_scale = 0.01;  // > 0
  bool noise = true;
  std::vector<SimFault> faults;

  // InvalidArgument naming the field: a time_scale that is not finite and
  // positive, a fault's negative at, count below 1, negative or non-finite delay_s.
  Status Check() const;
};

// Creates the world (renderer included) for `scene`. InvalidArgument for bad
// options (SimWorldOptions::Check).
Result<std::shared_ptr<SimWorld>> CreateSimWorld(const Scene& scene,
                                                 const SimWorldOptions& options);
const Renderer& WorldRenderer(const SimWorld& world);
double WorldTimeScale(const SimWorld& world);          // wall seconds per simulated second
double WorldTurntableAngleDeg(const SimWorld& world);  // measured angle now
// The disk the world's captures are written to: with a `disk_full` fault, a
// new QuotaStorage (sim_hw/quota_storage.h) that holds the fault's `at` frame
// files; null without one (captures write to the file system).
std::shared_ptr<CaptureStorage> MakeWorldCaptureStorage(const SimWorld& world);
// The world's turntable controller (sim_hw/sim_turntable_controller.h), which
// the `sim` turntable and the simulated Modbus controller drive.
class SimTurntableController;
SimTurntableController& WorldTurntableController(SimWorld& world);

// Sets a scene light's level (0..1) as a simulated panel does; NotFound for
// a light the scene lacks. For tests and benchmarks that need a lit world
// without building light devices.
Status SetWorldLightLevel(SimWorld& world, const std::string& light, double level);

// What a camera triggered now sees: the turntable angle and light levels at
// the start of its exposure (steady-clock time `trigger_ns`).
struct WorldExposure {
  double angle_deg = 0;
  std::vector<double> light_levels;
  int64_t trigger_ns = 0;
};
WorldExposure ExposeWorldNow(const SimWorld& world);
// Called with the ground-truth maps of every frame a simulated camera renders
// (scene camera index, turntable angle in deg), on the camera's thread.
using WorldTruthRecorder =
    std::function<void(int scene_camera, double turntable_deg, const ViewTruthMaps& maps)>;
// Installs `recorder` (empty: none). Frames rendered while one is installed
// also compute their maps.
void SetWorldTruthRecorder(SimWorld& world, WorldTruthRecorder recorder);
// Renders scene camera `scene_camera` for `exposure` as 8-bit BGR, with the
// world's noise setting; the same seed gives the same noise. The camera's last
// radiance is kept: a frame of the same turntable angle and light levels is
// only exposed again (bit-identical to a new render), unless a truth recorder
// is installed.
Result<cv::Mat> RenderWorldExposure(const SimWorld& world, int scene_camera,
                                    const WorldExposure& exposure, double exposure_s,
                                    double gain_db, uint64_t noise_seed);
// The RGGB Bayer mosaic a colour sensor would record of an 8-bit BGR image.
cv::Mat MosaicRGGB(const cv::Mat& bgr);
// Noise seed of frame `sequence` of camera `serial`: distinct per camera and frame.
uint64_t FrameNoiseSeed(const SimWorld& world, const std::string& serial, uint64_t sequence);
// The world's software trigger lines: simulated trigger lines pulse them and
// simulated cameras armed for a line listen on them.
TriggerBus& WorldTriggers(SimWorld& world);
// Counts one more trigger of camera `serial` and returns the configured
// camera fault (drop_frame, camera_gone, download_timeout) that hits it, or nullptr.
const SimFault* NextCameraFault(SimWorld& world, const std::string& serial);

// Registers the `sim` backend of every device kind; devices built from it act on `world`.
void RegisterSimBackends(DeviceRegistry* registry, std::shared_ptr<SimWorld> world);

}  // namespace hairrig
