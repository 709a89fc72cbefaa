#include "drivers/aravis_camera.h"

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>

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

// How many frames after frame id `from` the frame with id `to` is (1: the
// next one). GigE Vision's 16-bit block ids (and Aravis' fake's) run 1..65535
// and wrap to 1, skipping 0; other ids count up in 64 bits.
uint64_t FrameIdStep(uint64_t from, uint64_t to, bool skips_zero) {
  constexpr uint64_t kShortIds = 0xFFFF;
  if (skips_zero && from <= kShortIds && to <= kShortIds)
    return (to + kShortIds - from) % kShortIds;
  return to - from;
}
// A step past this is a frame id from before the last one, not a gap.
constexpr uint64_t kMaxFrameIdStep = 0x8000;

// "frame id B after A means N frame(s) lost, ..." or "... is out of sequence";
// `expected`: the step from A to B that is no gap (1, plus the buffers with
// id 0 between them).
std::string FrameIdGapText(uint64_t last, uint64_t id, uint64_t step, uint64_t expected) {
  std::string text = "frame id " + std::to_string(id) + " after " + std::to_string(last);
  if (expected > 1) text += " and " + std::to_string(expected - 1) + " buffer(s) without an id";
  if (step < expected || step > kMaxFrameIdStep) return text + " is out of sequence";
  return text + " means " + std::to_string(step - expected) +
         " frame(s) lost, dropped for want of a free stream buffer or on the network";
}

class AravisCamera : public Camera {
 public:
  AravisCamera(DeviceInfo info, AravisCameraOptions options)
      : Camera(std::move(info)), options_(std::move(options)) {}
  ~AravisCamera() override { (void)AravisCamera::DoClose(); }

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

  AravisStreamStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stream_ ? StatsLocked() : last_stats_;
  }

 protected:
  Status DoOpen() override {
    (void)Close();
    std::lock_guard<std::mutex> lock(mutex_);
    HR_ASSIGN_OR_RETURN(ArvCamera * camera, Connect());
    camera_.reset(camera);
    gone_ = false;
    ids_skip_zero_ =
        arv_camera_is_gv_device(camera) || ARV_IS_FAKE_DEVICE(arv_camera_get_device(camera));
    frame_ids_ = AravisFrameIds(ids_skip_zero_, ids_skip_zero_ || arv_camera_is_uv_device(camera));
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

  Status DoClose() override {
    (void)Disarm();
    std::lock_guard<std::mutex> lock(mutex_);
    if (camera_ && control_lost_handler_ != 0) {
      g_signal_handler_disconnect(arv_camera_get_device(camera_.get()), control_lost_handler_);
    }
    control_lost_handler_ = 0;
    camera_.reset();
    return Status::Ok();
  }

  Status DoHealthCheck() override {
    std::lock_guard<std::mutex> lock(mutex_);
    GError* error = nullptr;
    arv_camera_get_device_serial_number(camera_.get(), &error);
    if (error || gone_)
      return Fault(
          Unavailable("does not answer (" + TakeError(error) + "); check its cable and power"));
    return Status::Ok();
  }

  Status DoConfigure(const CaptureSettings& s) override {
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

  Status DoArm() override {
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
    // The stream's thread runs from its creation: what it counted before the
    // pool was full is no frame (Aravis' in-process fake counts an underrun
    // each time it polls an empty pool).
    underruns_at_arm_ = StreamUnderrunsLocked();
    arv_camera_start_acquisition(camera, &error);
    if (error) {
      stream_.reset();
      return Fault(IoError("starting acquisition: " + TakeError(error)));
    }
    sequence_ = 0;
    frame_ids_.Reset();
    triggers_.Clear();
    return Status::Ok();
  }

  Status DoDisarm() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stream_) {
      last_stats_ = StatsLocked();
      GError* error = nullptr;
      if (camera_) arv_camera_stop_acquisition(camera_.get(), &error);
      g_clear_error(&error);
      stream_.reset();
    }
    return Status::Ok();
  }

  Status DoSoftwareTrigger() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (gone_) return Fault(Unavailable("lost its control channel; reopen it"));
    const int64_t t = SteadyNowNs();
    GError* error = nullptr;
    arv_camera_software_trigger(camera_.get(), &error);
    if (error) return Fault(Unavailable("sending TriggerSoftware: " + TakeError(error)));
    triggers_.Sent(t);
    return Status::Ok();
  }

  Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) override {
    ArvStream* stream = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!frame_ids_.gap().ok()) return frame_ids_.gap();  // no frame pairs with its trigger now
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
      return Timeout(Describe() + ": no frame within " + std::to_string(timeout.count()) + " ms" +
                     UnderrunNoteLocked());
    }
    Result<Frame> frame = ToFrameLocked(buffer);
    arv_stream_push_buffer(stream, buffer);
    return frame;
  }

  void DoLineTriggerSent(int64_t sent_ns) override { triggers_.Sent(sent_ns); }

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

  guint64 StreamUnderrunsLocked() const {
    guint64 completed = 0, failures = 0, underruns = 0;
    if (stream_) arv_stream_get_statistics(stream_.get(), &completed, &failures, &underruns);
    return underruns;
  }

  // "; the stream found no free buffer N time(s) since arming, ..." or "".
  std::string UnderrunNoteLocked() const {
    const guint64 underruns = StreamUnderrunsLocked();
    if (underruns <= underruns_at_arm_) return "";
    return "; the stream found no free buffer " + std::to_string(underruns - underruns_at_arm_) +
           " time(s) since arming, and drops a frame arriving then (raise `buffers`, or take "
           "the frames sooner)";
  }

  // Every buffer answers one trigger, with an image or without: its trigger
  // is used up and its frame id checked before anything else.
  Result<Frame> ToFrameLocked(ArvBuffer* buffer) {
    const int64_t received_ns = SteadyNowNs();
    const int64_t trigger_ns =
        triggers_.ForFrame(received_ns, options_.nominal.LatencyWallS(settings_.exposure_s));
    const uint64_t frame_id = arv_buffer_get_frame_id(buffer);
    HR_RETURN_IF_ERROR(frame_ids_.Next(frame_id, Describe(), UnderrunNoteLocked()));
    const ArvBufferStatus status = arv_buffer_get_status(buffer);
    if (status != ARV_BUFFER_STATUS_SUCCESS) {
      return CorruptData(Describe() + ": frame arrived incomplete (Aravis buffer status " +
                         std::to_string(static_cast<int>(status)) + "); see the stream statistics");
    }
    if (ids_skip_zero_ && frame_id == 0) {
      return CorruptData(Describe() +
                         ": frame carries frame id 0, which GigE Vision reserves: the camera "
                         "sent no image for this trigger");
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
    frame.received_time_ns = received_ns;
    frame.trigger_time_ns = trigger_ns;
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
  bool ids_skip_zero_ = false;    // GigE Vision or Aravis' fake: frame id 0 is no image
  AravisFrameIds frame_ids_;      // of the buffers delivered since Arm
  guint64 underruns_at_arm_ = 0;  // the stream's underruns once its pool was full
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

Status AravisCameraOptions::Check() const {
  HR_RETURN_IF_ERROR(nominal.Check());
  if (buffers < 2 || buffers > 256)
    return InvalidArgument("buffers must lie in 2..256, got " + std::to_string(buffers));
  if (packet_size < 0 || packet_size > 16384) {
    return InvalidArgument("packet_size must lie in 0..16384 (0: negotiated), got " +
                           std::to_string(packet_size));
  }
  if (trigger_source.empty())
    return InvalidArgument("trigger_source must name a GenICam line (Line0)");
  return Status::Ok();
}

std::unique_ptr<Camera> MakeAravisCamera(const DeviceInfo& info, AravisCameraOptions options) {
  return std::make_unique<AravisCamera>(info, std::move(options));
}

void AravisFrameIds::Reset() {
  last_.reset();
  unnumbered_ = 0;
  gap_ = Status::Ok();
}

Status AravisFrameIds::Next(uint64_t id, const std::string& camera, const std::string& note) {
  if (!gap_.ok()) return gap_;
  if (id == 0) {
    if (last_) ++unnumbered_;
    return Status::Ok();
  }
  const std::optional<uint64_t> last = std::exchange(last_, id);
  const uint64_t expected = 1 + std::exchange(unnumbered_, 0);
  if (!last || !counts_frames_) return Status::Ok();
  const uint64_t step = FrameIdStep(*last, id, skips_zero_);
  if (step == expected) return Status::Ok();
  gap_ = CorruptData(camera + ": " + FrameIdGapText(*last, id, step, expected) + note +
                     "; the frames after it cannot be paired with their triggers, so none is "
                     "delivered until the camera is armed again: re-arm the camera");
  return gap_;
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
        HR_RETURN_IF_ERROR(options.Check().WithContext("camera " + c.name));
        const std::string where = options.address.empty() ? "found by serial" : options.address;
        return MakeAravisCamera(c.Info("Aravis camera (" + where + ")"), std::move(options));
      });
}

}  // namespace hairrig
