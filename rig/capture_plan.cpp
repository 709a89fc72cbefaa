#include "rig/capture_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace hairrig {

double RetryPolicy::BackoffBefore(int attempt) const {
  if (attempt <= 1) return 0;
  return backoff_s * std::pow(backoff_factor, attempt - 2);
}

uint64_t CapturePolicies::MinFreeBytes() const {
  constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
  const double bytes = min_free_mb * 1e6;
  if (!(bytes < static_cast<double>(kMax))) return kMax;  // also NaN
  return bytes > 0 ? static_cast<uint64_t>(bytes) : 0;
}

uint64_t BytesNeededToFinish(const CapturePlan& plan, const DeviceSet& devices,
                             const std::vector<int>& views, const CapturePolicies& policies) {
  const uint64_t bytes_per_pixel =
      static_cast<uint64_t>(std::max(1, BytesPerPixel(plan.camera_settings.format)));
  uint64_t total = policies.MinFreeBytes();
  for (int v : views) {
    const Camera* camera =
        devices.FindCameraBySerial(plan.views.at(static_cast<size_t>(v)).camera_serial);
    const CameraCapabilities caps = camera->capabilities();
    const uint64_t frame = static_cast<uint64_t>(std::max(0, caps.width_px)) *
                           static_cast<uint64_t>(std::max(0, caps.height_px)) * bytes_per_pixel;
    total = frame > std::numeric_limits<uint64_t>::max() - total
                ? std::numeric_limits<uint64_t>::max()
                : total + frame;
  }
  return total;
}

double StopLowerBoundS(const CapturePlan& plan, const DeviceSet& devices, double from_deg,
                       const PlannedStop& stop) {
  const Turntable& table = *devices.turntable;
  const double distance = std::abs(stop.angle_deg - from_deg);
  double s = 0;
  if (distance >= table.capabilities().resolution_deg) {
    s +=
        (MoveDurationS(distance, plan.motion) + table.capabilities().settle_s) * table.time_scale();
  }
  double exposure = 0;
  for (int v : stop.views) {
    const Camera* c = devices.FindCameraBySerial(plan.views[static_cast<size_t>(v)].camera_serial);
    exposure = std::max(exposure, plan.camera_settings.exposure_s * c->time_scale());
  }
  return s + exposure;
}

double PlanLowerBoundS(const CapturePlan& plan, const DeviceSet& devices, double from_deg) {
  double total = 0;
  for (const PlannedStop& stop : plan.stops) {
    total += StopLowerBoundS(plan, devices, from_deg, stop);
    from_deg = stop.angle_deg;
  }
  return total;
}

namespace {

constexpr double kMaxAngleDeg = 3600;  // ten turns either way
constexpr int kMaxStops = 3600;
// Free space to keep on the capture's disk, MB: 100 TB is more than any disk
// a rig writes to holds, so a larger value is a mistake (1e300 would refuse
// every capture as short of space).
constexpr double kMaxMinFreeMb = 1e8;

// "top, bottom": the names of `devices`' lights or cameras, for messages.
template <typename Device>
std::string NamesOf(const std::vector<std::unique_ptr<Device>>& devices) {
  std::string names;
  for (const auto& d : devices) names += (names.empty() ? "" : ", ") + d->info().name;
  return names.empty() ? "none" : names;
}

// Light name -> level from the map at `key`; a light the map leaves out is
// off, a name that is no configured light is an error (a typo must not
// switch a panel off), and so is a level between 0 and 1 for a light that
// is not dimmable (it would be switched fully on).
std::map<std::string, double> ReadLightLevels(const ConfigNode& node, const std::string& key,
                                              const DeviceSet& devices,
                                              const std::map<std::string, double>& fallback) {
  if (!node.Has(key)) return fallback;
  const ConfigNode levels = node.Child(key);
  std::map<std::string, double> out;
  for (const auto& light : devices.lights) {
    const std::string& name = light->info().name;
    const double level = levels.Number(name, 0.0, {.min = 0, .max = 1});
    out[name] = level;
    if (level > 0 && level < 1 && !light->capabilities().dimmable)
      levels.Fail(name, "light " + QuotedExcerpt(name) + " (backend " + light->info().backend +
                            ") is not dimmable: give 0 (off) or 1 (on)");
  }
  for (const std::string& name : levels.Keys()) {
    if (!out.count(name)) {
      levels.Fail(name, "no light named " + QuotedExcerpt(name) +
                            " in the devices section (lights: " + NamesOf(devices.lights) + ")");
    }
  }
  return out;
}

// The stop a view belongs to: same angle and light state as an existing stop.
int StopFor(CapturePlan* plan, double angle_deg, const std::map<std::string, double>& lights) {
  for (PlannedStop& s : plan->stops) {
    if (std::abs(s.angle_deg - angle_deg) < 1e-9 && s.light_levels == lights) return s.index;
  }
  PlannedStop stop;
  stop.index = static_cast<int>(plan->stops.size());
  stop.angle_deg = angle_deg;
  stop.light_levels = lights;
  plan->stops.push_back(stop);
  return stop.index;
}

// Adds `camera`'s view at `stop`; false (nothing added) when the stop has
// that camera's view already: the same view twice.
bool AddView(CapturePlan* plan, int stop, const Camera& camera) {
  PlannedStop& s = plan->stops[static_cast<size_t>(stop)];
  for (int view : s.views) {
    if (plan->views[static_cast<size_t>(view)].camera_name == camera.info().name) return false;
  }
  PlannedView v;
  v.index = static_cast<int>(plan->views.size());
  v.stop = stop;
  v.camera_name = camera.info().name;
  v.camera_serial = camera.info().serial;
  s.views.push_back(v.index);
  plan->views.push_back(v);
  return true;
}

std::string TwiceMessage(const Camera& camera, double angle_deg) {
  std::ostringstream s;
  s << "camera '" << camera.info().name << "' at " << angle_deg
    << " deg under the same lights is planned twice; each view is shot once";
  return s.str();
}

const Camera* CameraByName(const DeviceSet& devices, const std::string& name) {
  for (const auto& c : devices.cameras) {
    if (c->info().name == name) return c.get();
  }
  return nullptr;
}

std::string NoCameraMessage(const DeviceSet& devices, const std::string& name) {
  return "no camera named " + QuotedExcerpt(name) +
         " in the devices section (cameras: " + NamesOf(devices.cameras) + ")";
}

CaptureSettings ReadCameraSettings(const ConfigNode& plan) {
  CaptureSettings s;
  s.exposure_s = plan.Number("exposure_s", 0.02, {.min = 1e-6, .max = 60});
  s.gain_db = plan.Number("gain_db", 0.0, {.min = 0, .max = 48});
  const std::string format =
      plan.Choice("pixel_format", {"rgb8", "bgr8", "mono8", "bayer_rg8"}, "rgb8");
  s.format = format == "mono8"       ? PixelFormat::kMono8
             : format == "bgr8"      ? PixelFormat::kBgr8
             : format == "bayer_rg8" ? PixelFormat::kBayerRG8
                                     : PixelFormat::kRgb8;
  return s;
}

// `views: [{angle_deg, camera, lights}, ...]`.
void ReadExplicitViews(const ConfigNode& node, const DeviceSet& devices,
                       const std::map<std::string, double>& lights, CapturePlan* plan) {
  for (const ConfigNode& v : node.Items("views")) {
    v.AllowOnlyKeys({"angle_deg", "camera", "lights"});
    const double angle = v.Number("angle_deg", {.min = -kMaxAngleDeg, .max = kMaxAngleDeg});
    const std::string name = v.String("camera");
    const auto view_lights = ReadLightLevels(v, "lights", devices, lights);
    const Camera* camera = CameraByName(devices, name);
    if (!v.ok()) return;
    if (!camera) return v.Fail("camera", NoCameraMessage(devices, name));
    if (!AddView(plan, StopFor(plan, angle, view_lights), *camera))
      return v.Fail("", TwiceMessage(*camera, angle));
  }
}

// `stops: N` or `angles_deg: [...]`, times `cameras: [...]` (default: every camera).
void ReadStopsTimesCameras(const ConfigNode& node, const DeviceSet& devices,
                           const std::map<std::string, double>& lights, CapturePlan* plan) {
  std::vector<double> angles;
  if (node.Has("angles_deg")) {
    angles = node.Numbers("angles_deg", 0, {.min = -kMaxAngleDeg, .max = kMaxAngleDeg});
    if (angles.size() > static_cast<size_t>(kMaxStops)) {
      return node.Fail("angles_deg", std::to_string(angles.size()) + " stops, more than " +
                                         std::to_string(kMaxStops));
    }
  } else {
    const int stops = node.Integer("stops", 19, {.min = 1, .max = kMaxStops});
    for (int s = 0; s < stops; ++s) angles.push_back(360.0 * s / stops);
  }
  std::vector<const Camera*> cameras;
  if (node.Has("cameras")) {
    for (const std::string& name : node.Strings("cameras")) {
      const Camera* camera = CameraByName(devices, name);
      if (!camera) return node.Fail("cameras", NoCameraMessage(devices, name));
      cameras.push_back(camera);
    }
  } else {
    for (const auto& c : devices.cameras) cameras.push_back(c.get());
  }
  if (!node.ok()) return;
  for (double angle : angles) {
    const int stop = StopFor(plan, angle, lights);
    for (const Camera* c : cameras) {
      if (AddView(plan, stop, *c)) continue;
      return node.Fail(node.Has("angles_deg") ? "angles_deg" : "cameras", TwiceMessage(*c, angle));
    }
  }
}

}  // namespace

Result<CapturePlan> ReadCapturePlan(const ConfigNode& root, const DeviceSet& devices) {
  const ConfigNode node = root.OptionalChild("plan");
  CapturePlan plan;
  if (devices.cameras.empty())
    return InvalidArgument(root.file() + ": the rig has no cameras to capture with");
  std::map<std::string, double> all_on;
  for (const auto& light : devices.lights) all_on[light->info().name] = 1.0;
  // An absent section reads as an empty one: every field takes its default.
  if (node.IsMap())
    node.AllowOnlyKeys({"stops", "angles_deg", "cameras", "lights", "views", "speed_deg_s",
                        "accel_deg_s2", "home", "exposure_s", "gain_db", "pixel_format",
                        "trigger_pulse_us"});
  plan.motion.speed_deg_s = node.Number("speed_deg_s", 30, kTurntableSpeedRange);
  plan.motion.accel_deg_s2 = node.Number("accel_deg_s2", 60, kTurntableAccelRange);
  plan.home_first = node.Bool("home", true);
  plan.camera_settings = ReadCameraSettings(node);
  plan.trigger_pulse =
      std::chrono::microseconds(node.Integer("trigger_pulse_us", 100, {.min = 1, .max = 1000000}));
  const std::map<std::string, double> lights = ReadLightLevels(node, "lights", devices, all_on);
  if (node.Has("views")) {
    ReadExplicitViews(node, devices, lights, &plan);
  } else {
    ReadStopsTimesCameras(node, devices, lights, &plan);
  }
  if (!node.ok()) return node.status();
  if (plan.views.empty()) return InvalidArgument(node.Where() + ": the plan has no views");
  return plan;
}

Result<CapturePolicies> ReadCapturePolicies(const ConfigNode& root) {
  CapturePolicies p;
  const ConfigNode retries = root.OptionalChild("retries");
  if (retries.IsMap()) {
    retries.AllowOnlyKeys({"camera", "turntable", "light", "frame_timeout_s", "move_timeout_s"});
    for (auto [key, policy] :
         {std::pair{"camera", &p.camera}, {"turntable", &p.turntable}, {"light", &p.light}}) {
      const ConfigNode r = retries.OptionalChild(key);
      if (!r.IsMap()) continue;
      r.AllowOnlyKeys({"attempts", "backoff_s", "backoff_factor"});
      policy->attempts = r.Integer("attempts", policy->attempts, {.min = 1, .max = 100});
      policy->backoff_s = r.Number("backoff_s", policy->backoff_s, {.min = 0, .max = 600});
      policy->backoff_factor =
          r.Number("backoff_factor", policy->backoff_factor, {.min = 1, .max = 10});
    }
    p.frame_timeout_s =
        retries.Number("frame_timeout_s", p.frame_timeout_s, {.min = 0.01, .max = 3600});
    p.move_timeout_s =
        retries.Number("move_timeout_s", p.move_timeout_s, {.min = 0.01, .max = 3600});
    if (!retries.ok()) return retries.status();
  }
  const ConfigNode storage = root.OptionalChild("storage");
  if (storage.IsMap()) {
    storage.AllowOnlyKeys({"min_free_mb", "png_compression"});
    p.min_free_mb = storage.Number("min_free_mb", p.min_free_mb, {.min = 0, .max = kMaxMinFreeMb});
    p.png_compression = storage.Integer("png_compression", p.png_compression, {.min = 0, .max = 9});
    if (!storage.ok()) return storage.status();
  }
  return p;
}

}  // namespace hairrig
