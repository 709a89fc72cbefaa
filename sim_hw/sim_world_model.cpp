#include "sim_hw/sim_world_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/clock.h"
#include "core/status.h"
#include "drivers/turntable.h"
#include "sim_hw/quota_storage.h"
#include "sim_hw/renderer.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_faults.h"

namespace hairrig {
namespace detail {

double TrapezoidPosition(double distance, const MotionProfile& p, double t) {
  const double d = std::abs(distance);
  const double speed = p.speed_deg_s, accel = p.accel_deg_s2;
  const double duration = MoveDurationS(distance, p);
  const double t_acc = std::min(speed / accel, 0.5 * duration);
  const double peak = accel * t_acc;
  double pos;
  if (t < t_acc)
    pos = 0.5 * accel * t * t;
  else if (t < duration - t_acc)
    pos = 0.5 * peak * t_acc + peak * (t - t_acc);
  else
    pos = d - 0.5 * accel * std::pow(std::max(0.0, duration - t), 2);
  return std::copysign(std::min(pos, d), distance);
}

}  // namespace detail

Status SimWorldOptions::Check() const {
  if (!(time_scale > 0) || !std::isfinite(time_scale))
    return InvalidArgument("sim time_scale must be a positive number (1 = real time)");
  for (size_t i = 0; i < faults.size(); ++i) {
    const SimFault& f = faults[i];
    const std::string field = "sim faults[" + std::to_string(i) + "].";
    if (f.at < 0)
      return InvalidArgument(field + "at must be 0 or more, got " + std::to_string(f.at));
    if (f.count < 1)
      return InvalidArgument(field + "count must be at least 1, got " + std::to_string(f.count));
    if (!(f.delay_s >= 0) || !std::isfinite(f.delay_s))
      return InvalidArgument(field + "delay_s must be a finite number of seconds, 0 or more");
  }
  return Status::Ok();
}

Result<std::shared_ptr<SimWorld>> CreateSimWorld(const Scene& scene,
                                                 const SimWorldOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, Renderer::Create(scene));
  return std::make_shared<SimWorld>(std::move(renderer), options);
}
const Renderer& WorldRenderer(const SimWorld& world) { return world.renderer(); }
double WorldTimeScale(const SimWorld& world) { return world.time_scale(); }
double WorldTurntableAngleDeg(const SimWorld& world) { return world.AngleDeg(); }
std::shared_ptr<CaptureStorage> MakeWorldCaptureStorage(const SimWorld& world) {
  const SimFault* full = world.FindFault(SimFaultKind::kDiskFull);
  if (!full) return nullptr;
  QuotaStorageOptions options;
  options.frame_files = full->at;
  return std::make_shared<QuotaStorage>(options);
}
SimTurntableController& WorldTurntableController(SimWorld& world) {
  return world.turntable_controller();
}
TriggerBus& WorldTriggers(SimWorld& world) { return world.triggers(); }
void SetWorldTruthRecorder(SimWorld& world, WorldTruthRecorder recorder) {
  world.SetTruthRecorder(std::move(recorder));
}
Status SetWorldLightLevel(SimWorld& world, const std::string& light, double level) {
  return world.SetLightLevel(light, level);
}

WorldExposure ExposeWorldNow(const SimWorld& world) {
  return {world.AngleDeg(), world.LightLevels(), SteadyNowNs()};
}

Result<cv::Mat> RenderWorldExposure(const SimWorld& world, int scene_camera,
                                    const WorldExposure& exposure, double exposure_s,
                                    double gain_db, uint64_t noise_seed) {
  RenderOptions o;
  o.light_levels = exposure.light_levels;
  o.exposure_s = exposure_s;
  o.gain_db = gain_db;
  o.noise = world.noise();
  o.noise_seed = noise_seed;
  const auto recorder = world.truth_recorder();
  if (!recorder) {  // with a recorder every frame renders its maps
    if (auto cached = world.CachedRadianceFor(scene_camera, exposure)) {
      return world.renderer().Expose(scene_camera, cached->radiance, o);
    }
  }
  o.ground_truth = recorder != nullptr;
  o.keep_radiance = true;
  HR_ASSIGN_OR_RETURN(RenderedView view,
                      world.renderer().Render(scene_camera, exposure.angle_deg, o));
  if (recorder) (*recorder)(scene_camera, exposure.angle_deg, view.truth);
  world.CacheRadiance(scene_camera, exposure, std::move(view.radiance));
  return std::move(view.image);
}

cv::Mat MosaicRGGB(const cv::Mat& bgr) {
  cv::Mat bayer(bgr.rows, bgr.cols, CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int channel = (y % 2 == 0) ? (x % 2 == 0 ? 2 : 1) : (x % 2 == 0 ? 1 : 0);
      bayer.at<uint8_t>(y, x) = p[channel];
    }
  }
  return bayer;
}

uint64_t FrameNoiseSeed(const SimWorld& world, const std::string& serial, uint64_t sequence) {
  return std::hash<std::string>{}(serial) ^ (sequence * 0x9E3779B97F4A7C15ull) ^ world.scene().seed;
}

const SimFault* NextCameraFault(SimWorld& world, const std::string& serial) {
  return world.NextEventFault(serial, {SimFaultKind::kDropFrame, SimFaultKind::kCameraGone,
                                       SimFaultKind::kDownloadTimeout});
}

}  // namespace hairrig
