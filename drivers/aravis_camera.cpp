#include "drivers/aravis_camera.h"

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "drivers/camera_support.h"

namespace hairrig {
namespace {

// Takes a GError's message (and frees it); "" for none.
std::string TakeError(GError*& error) {
  if (error == nullptr) return "";
  std::string text = error->message ? error->message : "unknown error";
  g_clear_error(&error);
  return text;
}

struct GObjectUnref {
  void operator()(gpointer object) const {
    if (object != nullptr) g_object_unref(object);
  }
};
template <typename T>
using GPtr = std::unique_ptr<T, GObjectUnref>;

// The Aravis pixel format that carries `format`, and whether the frame must
// be debayered on the host (a Bayer camera asked for colour).
struct WireFormat {
  ArvPixelFormat arv = ARV_PIXEL_FORMAT_MONO_8;
  bool debayer = false;
};

int WireBytesPerPixel(ArvPixelFormat f) {
  return static_cast<int>(ARV_PIXEL_FORMAT_BIT_PER_PIXEL(f) / 8);
}

class AravisCamera : public Camera {
 public:
  AravisCamera(DeviceInfo info, AravisCameraOptions options)
      : Camera(std::move(info)), options_(std::move(options)) {}
  ~AravisCamera() override { (void)Close(); }

  double time_scale() const override { return options_.nominal.time_scale; }

  CameraCapabilities capabilities() const override {
    return {.width_px = width_px_,
            .height_px = height_px_,
            .formats = {PixelFormat::kMono8, PixelFormat::kRgb8, PixelFormat::kBgr8,
                        PixelFormat::kBayerRG8},
            .min_exposure_s = min_exposure_s_,
            .max_exposure_s = max_exposure_s_,
            .line_trigger = true,
            .readout_s = options_.nominal.readout_s,
            .download_s = options_.nominal.download_s};
  }

  Status Open() override {
    (void)Close();
    std::lock_guard<std::mutex> lock(mutex_);
    HR_ASSIGN_OR_RETURN(ArvCamera * camera, Connect());
    camera_.reset(camera);
    gone_ = false;
    control_lost_handler_ = g_signal_connect(arv_camera_get_device(camera), "control-lost",
                                             G_CALLBACK(&AravisCamera::OnControlLost), this);
    GError* error = nullptr;
    int sensor_w = 0, sensor_h = 0;
    arv_camera_get_sensor_size(camera, &sensor_w, &sensor_h, &error);
    if (error) return FailOpen(IoError("reading the sensor size: " + TakeError(error)));
    width_px_ = options_.nominal.width_px > 0 ? options_.nominal.width_px : sensor_w;
    height_px_ = options_.nominal.height_px > 0 ? options_.nominal.height_px : sensor_h;
    if (width_px_ > sensor_w || height_px_ > sensor_h) {
      return FailOpen(OutOfRange("the region " + std::to_string(width_px_) + "x" +
                                 std::to_string(height_px_) + " exceeds the sensor's " +
                                 std::to_string(sensor_w) + "x" + std::to_string(sensor_h)));
    }
    arv_camera_set_region(camera, 0, 0, width_px_, height_px_, &error);
    if (error) return FailOpen(IoError("setting the region: " + TakeError(error)));
    if (options_.packet_size > 0 && arv_camera_is_gv_device(camera)) {
      arv_camera_gv_set_packet_size(camera, options_.packet_size, &error);
      if (error) return FailOpen(IoError("setting the packet size: " + TakeError(error)));
    }
    double lo_us = 0, hi_us = 0;
    arv_camera_get_exposure_time_bounds(camera, &lo_us, &hi_us, &error);
    if (error) return FailOpen(IoError("reading the exposure bounds: " + TakeError(error)));
    min_exposure_s_ = lo_us * 1e-6;
    max_exposure_s_ = hi_us * 1e-6;
    SetState(DeviceState::kReady);
    return Status::Ok();
  }

  Status Close() override {
    (void)Disarm();
    std::lock_guard<std::mutex> lock(mutex_);
    if (camera_ && control_lost_handler_ != 0) {
      g_signal_handler_disconnect(arv_camera_get_device(camera_.get()), control_lost_handler_);
    }
    control_lost_handler_ = 0;
    camera_.reset();
    SetState(DeviceState::kClosed);
    return Status::Ok();
  }

  Status HealthCheck() override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady, DeviceState::kBusy}, "HealthCheck"));
    std::lock_guard<std::mutex> lock(mutex_);
    GError* error = nullptr;
    arv_camera_get_device_serial_number(camera_.get(), &error);
    if (error || gone_)
      return Fault(
          Unavailable("does not answer (" + TakeError(error) + "); check its cable and power"));
    return Status::Ok();
  }

  Status Configure(const CaptureSettings& s) override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Configure"));
    HR_RETURN_IF_ERROR(CheckExposure(*this, capabilities(), s.exposure_s));
    if (s.format == PixelFormat::kEncoded)
      return OutOfRange(Describe() + ": delivers raw frames only");
    std::lock_guard<std::mutex> lock(mutex_);
    ArvCamera* camera = camera_.get();
    HR_ASSIGN_OR_RETURN(wire_, ChooseWireFormat(s.format));
    GError* error = nullptr;
    arv_camera_set_pixel_format(camera, wire_.arv, &error);
    if (!error) arv_camera_set_exposure_time(camera, s.exposure_s * 1e6, &error);
    if (!error) arv_camera_set_gain(camera, s.gain_db, &error);
    if (!error) arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    if (!error) {
      const std::string source =
          s.trigger == TriggerSource::kLine ? options_.trigger_source : "Software";
      arv_camera_set_trigger(camera, source.c_str(), &error);
    }
    if (error) return Fault(IoError("configuring: " + TakeError(error)));
    settings_ = s;
    return Status::Ok();
  }

  Status Arm() override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "Arm"));
    std::lock_guard<std::mutex> lock(mutex_);
    ArvCamera* camera = camera_.get();
    GError* error = nullptr;
    stream_.reset(arv_camera_create_stream(camera, nullptr, nullptr, &error));
    if (error || !stream_) return Fault(IoError("creating the stream: " + TakeError(error)));
    if (ARV_IS_GV_STREAM(stream_.get())) {
      // On loopback the kernel's default socket buffer drops packets; AUTO sizes it to a frame.
      g_object_set(stream_.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, nullptr);
    }
    // Some cameras (Aravis' fake among them) report no payload: compute it.
    size_t payload = arv_camera_get_payload(camera, &error);
    g_clear_error(&error);
    const size_t computed =
        static_cast<size_t>(width_px_) * height_px_ * WireBytesPerPixel(wire_.arv);
    payload = std::max(payload, computed);
    for (int i = 0; i < options_.buffers; ++i)
      arv_stream_push_buffer(stream_.get(), arv_buffer_new(payload, nullptr));
    arv_camera_start_acquisition(camera, &error);
    if (error) {
      stream_.reset();
      return Fault(IoError("starting acquisition: " + TakeError(error)));
    }
    sequence_ = 0;
    underruns_seen_ = 0;
    triggers_.Clear();
    SetState(DeviceState::kBusy);
    return Status::Ok();
  }

  Status Disarm() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stream_) {
      last_stats_ = StatsLocked();
      GError* error = nullptr;
      if (camera_) arv_camera_stop_acquisition(camera_.get(), &error);
      g_clear_error(&error);
      stream_.reset();
    }
    if (state() == DeviceState::kBusy) SetState(DeviceState::kReady);
    return Status::Ok();
  }

  Status SoftwareTrigger() override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kBusy}, "SoftwareTrigger (after Arm)"));
    std::lock_guard<std::mutex> lock(mutex_);
    if (gone_) return Fault(Unavailable("lost its control channel; reopen it"));
    const int64_t t = SteadyNowNs();
    GError* error = nullptr;
    arv_camera_software_trigger(camera_.get(), &error);
    if (error) return Fault(Unavailable("sending TriggerSoftware: " + TakeError(error)));
    triggers_.Sent(t);
    return Status::Ok();
  }

  Result<Frame> WaitFrame(std::chrono::milliseconds timeout) override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kBusy}, "WaitFrame (after Arm)"));
    ArvStream* stream = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stream = stream_.get();
    }
    ArvBuffer* buffer =
        arv_stream_timeout_pop_buffer(stream, static_cast<guint64>(timeout.count()) * 1000);
    std::lock_guard<std::mutex> lock(mutex_);
    if (gone_) {
      if (buffer) arv_stream_push_buffer(stream, buffer);
      return Fault(Unavailable("lost its control channel (unplugged or powered off?); reopen it"));
    }
    if (buffer == nullptr) {
      return Timeout(Describe() + ": no frame within " + std::to_string(timeout.count()) + " ms");
    }
    Result<Frame> frame = ToFrameLocked(buffer);
    arv_stream_push_buffer(stream, buffer);
    HR_RETURN_IF_ERROR(CheckNoFrameLostLocked());
    return frame;
  }

  void LineTriggerSent(int64_t sent_ns) override { triggers_.Sent(sent_ns); }

  AravisStreamStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stream_ ? StatsLocked() : last_stats_;
  }

 private:
  static void OnControlLost(ArvDevice*, gpointer self) {
    static_cast<AravisCamera*>(self)->gone_ = true;
  }

  Status FailOpen(const Status& s) {
    camera_.reset();
    return Fault(s);
  }

  // Opens by address, or by searching the interfaces for the serial.
  Result<ArvCamera*> Connect() {
    GError* error = nullptr;
    std::string id = options_.address;
    ArvCamera* camera = nullptr;
    if (options_.connect) {
      auto connected = options_.connect();
      if (!connected.ok()) return Fault(connected.status());
      camera = *connected;
      id = options_.connect_name.empty() ? "the camera the rig connected" : options_.connect_name;
    } else if (id.empty()) {
      arv_update_device_list();
      std::string seen;
      for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
        const char* serial = arv_get_device_serial_nbr(i);
        if (serial && info().serial == serial) id = arv_get_device_id(i);
        seen += (seen.empty() ? "" : ", ") + std::string(arv_get_device_id(i));
      }
      if (id.empty()) {
        return Fault(Unavailable(
            "not found on any Aravis interface (" +
            (seen.empty() ? std::string("none found") : "found: " + seen) +
            "); check its cable, power and network settings (arv-tool-0.8 lists cameras)"));
      }
    }
    if (camera == nullptr) camera = arv_camera_new(id.c_str(), &error);
    if (camera == nullptr)
      return Fault(Unavailable("cannot open '" + id + "': " + TakeError(error)));
    const char* serial = arv_camera_get_device_serial_number(camera, &error);
    const std::string actual = serial ? serial : "";
    if (error || actual != info().serial) {
      g_object_unref(camera);
      return Fault(Unavailable("'" + id + "' has serial '" + actual + "', not '" + info().serial +
                               "'" + (error ? " (" + TakeError(error) + ")" : "")));
    }
    return camera;
  }

  Result<WireFormat> ChooseWireFormat(PixelFormat wanted) {
    GError* error = nullptr;
    guint n = 0;
    gint64* formats = arv_camera_dup_available_pixel_formats(camera_.get(), &n, &error);
    if (error) return Fault(IoError("listing pixel formats: " + TakeError(error)));
    auto has = [&](ArvPixelFormat f) {
      return std::find(formats, formats + n, static_cast<gint64>(f)) != formats + n;
    };
    WireFormat w;
    bool ok = true;
    switch (wanted) {
      case PixelFormat::kMono8:
        w.arv = ARV_PIXEL_FORMAT_MONO_8;
        ok = has(w.arv);
        break;
      case PixelFormat::kBayerRG8:
        w.arv = ARV_PIXEL_FORMAT_BAYER_RG_8;
        ok = has(w.arv);
        break;
      case PixelFormat::kRgb8:
      case PixelFormat::kBgr8:
        if (has(ARV_PIXEL_FORMAT_RGB_8_PACKED)) {
          w.arv = ARV_PIXEL_FORMAT_RGB_8_PACKED;
        } else {
          w = {ARV_PIXEL_FORMAT_BAYER_RG_8, true};
          ok = has(w.arv);
        }
        break;
      case PixelFormat::kEncoded:
        ok = false;
        break;
    }
    g_free(formats);
    if (!ok) return OutOfRange(Describe() + ": cannot deliver " + PixelFormatName(wanted));
    return w;
  }

  // A frame that arrived with no free buffer is dropped by the stream unseen:
  // its trigger cannot be told from the next one's, so the pairing of frames
  // and triggers is lost until the camera is armed again.
  Status CheckNoFrameLostLocked() {
    if (!stream_) return Status::Ok();  // disarmed meanwhile: the next Arm starts afresh
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(stream_.get(), &completed, &failures, &underruns);
    if (underruns == underruns_seen_) return Status::Ok();
    const guint64 lost = underruns - underruns_seen_;
    underruns_seen_ = underruns;
    return CorruptData(
        Describe() + ": " + std::to_string(lost) +
        " frame(s) lost for want of a free stream buffer, so later frames cannot be paired with "
        "their triggers; the camera must be armed again (raise `buffers` if this recurs)");
  }

  Result<Frame> ToFrameLocked(ArvBuffer* buffer) {
    const ArvBufferStatus status = arv_buffer_get_status(buffer);
    if (status != ARV_BUFFER_STATUS_SUCCESS) {
      // The camera answered a trigger, though the frame is lost.
      (void)triggers_.ForFrame(SteadyNowNs(), 0);
      return CorruptData(Describe() + ": frame arrived incomplete (Aravis buffer status " +
                         std::to_string(static_cast<int>(status)) + "); see the stream statistics");
    }
    const int w = arv_buffer_get_image_width(buffer);
    const int h = arv_buffer_get_image_height(buffer);
    const ArvPixelFormat f = arv_buffer_get_image_pixel_format(buffer);
    // The size the buffer reports can be 0 (Aravis' fake): the geometry is
    // checked instead, and every pushed buffer holds a full frame of it.
    const auto* data = static_cast<const uint8_t*>(arv_buffer_get_data(buffer, nullptr));
    if (w != width_px_ || h != height_px_ || f != wire_.arv) {
      return CorruptData(Describe() + ": frame is " + std::to_string(w) + "x" + std::to_string(h) +
                         ", format 0x" + std::to_string(f) + "; configured " +
                         std::to_string(width_px_) + "x" + std::to_string(height_px_));
    }
    Frame frame;
    frame.camera_serial = info().serial;
    frame.sequence = sequence_++;
    frame.width_px = w;
    frame.height_px = h;
    frame.format = settings_.format;
    frame.exposure_s = settings_.exposure_s;
    frame.gain_db = settings_.gain_db;
    frame.received_time_ns = SteadyNowNs();
    frame.trigger_time_ns = triggers_.ForFrame(frame.received_time_ns,
                                               options_.nominal.LatencyWallS(settings_.exposure_s));
    const cv::Mat wire(h, w, WireBytesPerPixel(f) == 3 ? CV_8UC3 : CV_8UC1,
                       const_cast<uint8_t*>(data));
    cv::Mat out;
    if (wire_.debayer) {
      // OpenCV names a Bayer pattern by the 2x2 block at (1,1): an RGGB sensor is "BG".
      cv::cvtColor(
          wire, out,
          settings_.format == PixelFormat::kRgb8 ? cv::COLOR_BayerBG2RGB : cv::COLOR_BayerBG2BGR);
    } else if (settings_.format == PixelFormat::kBgr8) {
      cv::cvtColor(wire, out, cv::COLOR_RGB2BGR);
    } else {
      out = wire;
    }
    frame.data.assign(out.datastart, out.dataend);
    return frame;
  }

  AravisStreamStats StatsLocked() const {
    AravisStreamStats s;
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(stream_.get(), &completed, &failures, &underruns);
    s.completed = completed;
    s.failures = failures;
    s.underruns = underruns;
    if (ARV_IS_GV_STREAM(stream_.get())) {
      guint64 resent = 0, missing = 0;
      arv_gv_stream_get_statistics(ARV_GV_STREAM(stream_.get()), &resent, &missing);
      s.resent_packets = resent;
      s.missing_packets = missing;
    }
    return s;
  }

  AravisCameraOptions options_;
  mutable std::mutex mutex_;  // Aravis feature access is not thread-safe
  GPtr<ArvCamera> camera_;
  GPtr<ArvStream> stream_;
  gulong control_lost_handler_ = 0;
  std::atomic<bool> gone_{false};
  CaptureSettings settings_;
  WireFormat wire_;
  int width_px_ = 0;
  int height_px_ = 0;
  double min_exposure_s_ = 0;
  double max_exposure_s_ = 0;
  uint64_t sequence_ = 0;
  TriggerTimes triggers_;
  guint64 underruns_seen_ = 0;  // stream underruns already reported, since Arm
  AravisStreamStats last_stats_;
};

}  // namespace

Result<AravisCameraOptions> ParseAravisCameraOptions(const ConfigNode& device) {
  device.AllowOnlyKeys({"name", "backend", "serial", "address", "width_px", "height_px", "buffers",
                        "packet_size", "trigger_line", "trigger_source", "readout_s",
                        "download_s"});
  AravisCameraOptions o;
  o.address = device.String("address", "");
  o.nominal = ReadCameraNominal(device, o.nominal);
  o.buffers = device.Integer("buffers", o.buffers, {.min = 2, .max = 256});
  o.packet_size = device.Integer("packet_size", 0, {.min = 0, .max = 16384});
  o.trigger_source = device.String("trigger_source", o.trigger_source);
  if (!device.ok()) return device.status();
  return o;
}

std::unique_ptr<Camera> MakeAravisCamera(const DeviceInfo& info, AravisCameraOptions options) {
  return std::make_unique<AravisCamera>(info, std::move(options));
}

AravisStreamStats AravisCameraStreamStats(const Camera& camera) {
  const auto* aravis = dynamic_cast<const AravisCamera*>(&camera);
  return aravis != nullptr ? aravis->stats() : AravisStreamStats{};
}

std::vector<AravisDetected> DetectAravisCameras() {
  arv_update_device_list();
  std::vector<AravisDetected> found;
  auto text = [](const char* s) { return std::string(s ? s : ""); };
  for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
    found.push_back({text(arv_get_device_id(i)), text(arv_get_device_vendor(i)),
                     text(arv_get_device_model(i)), text(arv_get_device_serial_nbr(i)),
                     text(arv_get_device_address(i)), text(arv_get_device_protocol(i))});
  }
  return found;
}

void RegisterAravisBackend(DeviceRegistry* registry, AravisOptionsHook hook) {
  registry->AddBackend<Camera>(
      DeviceKind::kCamera, "aravis",
      [hook](const DeviceConfig& c) -> Result<std::unique_ptr<Camera>> {
        HR_ASSIGN_OR_RETURN(AravisCameraOptions options, ParseAravisCameraOptions(c.node));
        if (hook) HR_RETURN_IF_ERROR(hook(c, &options));
        const std::string where = options.address.empty() ? "found by serial" : options.address;
        return MakeAravisCamera(c.Info("Aravis camera (" + where + ")"), std::move(options));
      });
}

}  // namespace hairrig
