#include "sim_hw/sim_aravis.h"

#include <arv.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <set>
#include <thread>

#include "sim_hw/gvcp_guard.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {

namespace {

// The buffer size Aravis' fake camera checks a buffer against before it is
// filled, computed as it does (32-bit arithmetic: it wraps).
uint64_t FakePayloadBytes(int width, int height, ArvPixelFormat format) {
  const uint32_t bits = ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format);
  return static_cast<uint32_t>(width) * static_cast<uint32_t>(height) * bits / 8u;
}

}  // namespace

class SimAravisFeed::Impl {
 public:
  Impl(std::shared_ptr<SimWorld> world, SimAravisOptions options)
      : world_(std::move(world)), options_(std::move(options)) {}
  ~Impl() { Detach(); }

  void Detach() {
    detaching_ = true;  // a fill waiting for its trigger gives up
    if (subscription_ != 0)
      WorldTriggers(*world_).Unsubscribe(options_.trigger_line, subscription_);
    subscription_ = 0;
    if (fake_ == nullptr) return;
    arv_fake_camera_set_fill_pattern(fake_, nullptr, nullptr);  // back to Aravis' own pattern
    g_object_unref(fake_);
    fake_ = nullptr;
    gige_ = nullptr;
  }

  // Holds a reference to `fake`, so that it outlives the camera that streams
  // it; `gige` (which owns `fake`) outlives the feed's use of it. Detach
  // leaves `gige` alone: SimGigECamera drops it before its feed detaches.
  void Attach(ArvFakeCamera* fake, ArvGvFakeCamera* gige) {
    Detach();
    detaching_ = false;
    gige_ = gige;
    // A frame withheld last left the GigE fake dropping every packet; the
    // feed's fill lifts that before each frame, Aravis' own pattern would not.
    if (gige != nullptr) g_object_set(gige, "gvsp-lost-ratio", 0.0, nullptr);
    fake_ = static_cast<ArvFakeCamera*>(g_object_ref(fake));
    arv_fake_camera_set_trigger_frequency(fake, 1000.0);
    if (options_.render || gige == nullptr)
      arv_fake_camera_set_fill_pattern(fake, &Impl::Fill, this);
    if (!options_.trigger_line.empty()) {
      subscription_ =
          WorldTriggers(*world_).Subscribe(options_.trigger_line, [this] { OnPulse(); });
    }
  }

  // Attaches again to the GigE fake it feeds, rendering or not (`render`);
  // the in-process fake is always rendered.
  void SetRender(bool render) {
    options_.render = render;
    if (fake_ == nullptr || gige_ == nullptr) return;
    auto* fake = static_cast<ArvFakeCamera*>(g_object_ref(fake_));
    Attach(fake, gige_);
    g_object_unref(fake);
  }

  int frames() const { return frames_.load(); }
  const SimAravisOptions& options() const { return options_; }

 private:
  static constexpr guint32 kLine0 = 0;
  static constexpr guint32 kSoftware = 1;

  guint32 Register(guint32 address) const {
    guint32 value = 0;
    arv_fake_camera_read_register(fake_, address, &value);
    return value;
  }
  bool InTriggerMode(guint32 source) const {
    return Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_MODE) == 1 &&
           Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOURCE) == source;
  }

  // A pulse on the wired line: a fake in Line0 trigger mode takes a frame of
  // the world as it is now, while it acquires (a camera ignores triggers
  // between AcquisitionStop and AcquisitionStart).
  void OnPulse() {
    if (!InTriggerMode(kLine0) || arv_fake_camera_get_acquisition_status(fake_) == 0) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pulse_exposures_.push_back(ExposeWorldNow(*world_));
    }
    if (gige_ != nullptr) {
      // The GigE fake produces frames on software triggers only: present the pulse as one.
      arv_fake_camera_write_register(fake_, ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOURCE, kSoftware);
      arv_fake_camera_write_register(fake_, ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOFTWARE, 1);
    }
  }

  // The phase of the stream whose thread runs the fill. The in-process fake
  // runs a thread per stream, from the stream's creation (before the
  // acquisition starts) until the stream is dropped; the backend makes a
  // stream per Arm and drops it after AcquisitionStop.
  enum class StreamPhase { kBeforeStart, kAcquiring, kStopped };

  // The in-process fake streams continuously whatever its trigger mode; the
  // feed holds each frame until its trigger arrives, as a real camera does.
  // False when the acquisition stops (or the feed detaches) first: the buffer
  // then goes to a stream that is being dropped, at once, so that dropping it
  // does not wait.
  bool AwaitTrigger() {
    thread_local StreamPhase phase = StreamPhase::kBeforeStart;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    for (;;) {
      if (detaching_) return false;
      if (arv_fake_camera_get_acquisition_status(fake_) == 0) {
        if (phase == StreamPhase::kAcquiring) {
          phase = StreamPhase::kStopped;
          std::lock_guard<std::mutex> lock(mutex_);
          pulse_exposures_.clear();  // AcquisitionStop aborts the frames not yet sent
        }
        if (phase == StreamPhase::kStopped) return false;
        // Not started yet; a stream dropped without a start must not hang its thread.
        if (std::chrono::steady_clock::now() > give_up) return false;
      } else {
        phase = StreamPhase::kAcquiring;
        if (InTriggerMode(kSoftware)) {
          if (arv_fake_camera_check_and_acknowledge_software_trigger(fake_)) return true;
        } else if (InTriggerMode(kLine0)) {
          std::lock_guard<std::mutex> lock(mutex_);
          if (!pulse_exposures_.empty()) return true;
        } else {
          return true;  // free running
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  static void Fill(ArvBuffer* buffer, void* data, guint32 exposure_time_us, guint32 gain,
                   ArvPixelFormat format) {
    auto* self = static_cast<Impl*>(data);
    // The GigE fake sends what the fill leaves, its status unchecked.
    if (self->gige_ != nullptr) g_object_set(self->gige_, "gvsp-lost-ratio", 0.0, nullptr);
    if (!self->Render(buffer, exposure_time_us, gain, format)) self->Withhold(buffer);
  }

  // A frame without the view is never served as an image: its buffer gets
  // frame id 0, which GigE Vision reserves and the fake never gives, and the
  // GigE fake drops every packet of it (its count of frame ids goes on, so
  // the client sees a gap). Should an Attach lift the drop while the GigE
  // fake still sends the frame, its packets carry id 0: the client's stream
  // discards them as late, or delivers a frame with id 0.
  void Withhold(ArvBuffer* buffer) {
    arv_buffer_set_frame_id(buffer, 0);
    if (gige_ != nullptr) g_object_set(gige_, "gvsp-lost-ratio", 1.0, nullptr);
  }

  // Fills `buffer` with the view of the frame's trigger; false when it
  // cannot (the buffer then holds no view).
  bool Render(ArvBuffer* buffer, guint32 exposure_time_us, guint32 gain, ArvPixelFormat format) {
    if (gige_ == nullptr && !AwaitTrigger()) return false;
    WorldExposure exposure;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!pulse_exposures_.empty()) {
        exposure = pulse_exposures_.front();
        pulse_exposures_.pop_front();
        if (gige_ != nullptr) {
          arv_fake_camera_write_register(fake_, ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOURCE, kLine0);
        }
      } else {
        exposure = ExposeWorldNow(*world_);
      }
    }
    const int w = arv_buffer_get_image_width(buffer);
    const int h = arv_buffer_get_image_height(buffer);
    auto* out = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
    const uint64_t sequence = static_cast<uint64_t>(frames_.fetch_add(1));
    auto image = RenderWorldExposure(*world_, options_.scene_camera, exposure,
                                     exposure_time_us * 1e-6, static_cast<double>(gain),
                                     FrameNoiseSeed(*world_, options_.serial, sequence));
    if (!image.ok() || out == nullptr) return false;
    cv::Mat converted;
    int type = CV_8UC1;
    switch (format) {
      case ARV_PIXEL_FORMAT_RGB_8_PACKED:
        cv::cvtColor(*image, converted, cv::COLOR_BGR2RGB);
        type = CV_8UC3;
        break;
      case ARV_PIXEL_FORMAT_BAYER_RG_8:
        converted = MosaicRGGB(*image);
        break;
      case ARV_PIXEL_FORMAT_MONO_16: {
        cv::Mat grey;
        cv::cvtColor(*image, grey, cv::COLOR_BGR2GRAY);
        grey.convertTo(converted, CV_16UC1, 257.0);
        type = CV_16UC1;
        break;
      }
      default:
        cv::cvtColor(*image, converted, cv::COLOR_BGR2GRAY);
        break;
    }
    // Width, height and pixel format are registers a GigE client writes; the
    // buffer holds at least what the fake computes from them, which may wrap.
    const uint64_t bytes = static_cast<uint64_t>(w) * static_cast<uint64_t>(h) * CV_ELEM_SIZE(type);
    if (w <= 0 || h <= 0 || bytes > FakePayloadBytes(w, h, format)) return false;
    // The camera's region is its top-left w x h; outside the render is black.
    cv::Mat target(h, w, type, out);
    target.setTo(0);
    const cv::Rect overlap(0, 0, std::min(w, converted.cols), std::min(h, converted.rows));
    converted(overlap).copyTo(target(overlap));
    return true;
  }

  std::shared_ptr<SimWorld> world_;
  SimAravisOptions options_;
  ArvFakeCamera* fake_ = nullptr;
  int subscription_ = 0;
  std::mutex mutex_;
  std::deque<WorldExposure> pulse_exposures_;  // the world at each pulse not yet rendered
  ArvGvFakeCamera* gige_ = nullptr;            // the GigE fake serving fake_; null in-process
  std::atomic<bool> detaching_{false};
  std::atomic<int> frames_{0};  // made for a trigger, withheld ones included
};

SimAravisFeed::SimAravisFeed(std::shared_ptr<SimWorld> world, SimAravisOptions options)
    : impl_(std::make_unique<Impl>(std::move(world), std::move(options))) {}
SimAravisFeed::~SimAravisFeed() = default;
void SimAravisFeed::Attach(ArvFakeCamera* fake, ArvGvFakeCamera* gige) {
  impl_->Attach(fake, gige);
}
void SimAravisFeed::SetRender(bool render) { impl_->SetRender(render); }
int SimAravisFeed::frames_rendered() const { return impl_->frames(); }

Status SimAravisOptions::Check() const {
  if (serial.empty())
    return InvalidArgument("serial (the camera's DeviceSerialNumber) is required");
  if (scene_camera < 0) {
    return InvalidArgument("scene_camera must be 0 or more, got " + std::to_string(scene_camera));
  }
  return Status::Ok();
}

Result<ArvCamera*> OpenSimAravisCamera(SimAravisFeed& feed, const SimAravisOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("simulated Aravis camera"));
  GError* error = nullptr;
  ArvDevice* device = arv_fake_device_new(options.serial.c_str(), &error);
  if (device == nullptr) {
    const std::string text = error ? error->message : "unknown error";
    g_clear_error(&error);
    return Internal("Aravis fake device " + options.serial + ": " + text);
  }
  feed.Attach(arv_fake_device_get_fake_camera(ARV_FAKE_DEVICE(device)));
  ArvCamera* camera = arv_camera_new_with_device(device, &error);
  g_object_unref(device);  // the camera holds it
  if (camera == nullptr) {
    const std::string text = error ? error->message : "unknown error";
    g_clear_error(&error);
    return Internal("Aravis fake camera " + options.serial + ": " + text);
  }
  return camera;
}

class SimGigECamera::Impl {
 public:
  Impl(std::shared_ptr<SimWorld> world, const SimAravisOptions& opts)
      : feed(std::move(world), opts), options(opts) {}
  ~Impl() {
    if (gv != nullptr)
      g_object_unref(gv);  // stops serving; the feed releases the fake camera after
  }
  SimAravisFeed feed;
  SimAravisOptions options;
  ArvGvFakeCamera* gv = nullptr;
  std::string address = "127.0.0.1";
};

Result<std::unique_ptr<SimGigECamera>> SimGigECamera::Start(std::shared_ptr<SimWorld> world,
                                                            SimAravisOptions options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("simulated GigE Vision camera"));
  auto impl = std::make_unique<Impl>(world, options);
  const std::set<uint64_t> before = OpenSocketInodes();
  impl->gv = arv_gv_fake_camera_new(impl->address.c_str(), options.serial.c_str());
  if (impl->gv == nullptr || !arv_gv_fake_camera_is_running(impl->gv)) {
    return Unavailable("simulated GigE Vision camera " + options.serial +
                       ": Aravis cannot serve on " + impl->address +
                       ":3956 (is the loopback interface up?)");
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(impl->gv);
  size_t genicam_bytes = 0;
  arv_fake_camera_get_genicam_xml(fake, &genicam_bytes);
  const GvcpMemoryLimits limits{static_cast<uint32_t>(ARV_FAKE_CAMERA_MEMORY_SIZE + genicam_bytes),
                                ARV_FAKE_CAMERA_MEMORY_SIZE};
  HR_RETURN_IF_ERROR(GuardGvFakeSockets(before, impl->address, limits).status());
  const Status sole = RequireSoleGvcpServer(before, impl->address);
  if (!sole.ok()) {
    return Unavailable("simulated GigE Vision camera " + options.serial + ": " + sole.message() +
                       "; stop the other one (a `hairrig sim serve`, a benchmark, "
                       "arv-fake-gv-camera-0.8)");
  }
  // The fake starts at 512 x 512; a client sees the scene camera's full frame.
  const auto& intrinsics = WorldRenderer(*world)
                               .scene()
                               .cameras.at(static_cast<size_t>(options.scene_camera))
                               .intrinsics;
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH,
                                 static_cast<guint32>(intrinsics.width_px));
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT,
                                 static_cast<guint32>(intrinsics.height_px));
  impl->feed.Attach(fake, impl->gv);
  return std::unique_ptr<SimGigECamera>(new SimGigECamera(std::move(impl)));
}

SimGigECamera::SimGigECamera(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SimGigECamera::~SimGigECamera() = default;
const std::string& SimGigECamera::address() const { return impl_->address; }
const std::string& SimGigECamera::serial() const { return impl_->options.serial; }
int SimGigECamera::frames_rendered() const { return impl_->feed.frames_rendered(); }
void SimGigECamera::SetRender(bool render) { impl_->feed.SetRender(render); }
std::string SimGigECamera::Describe() const {
  return "simulated GigE Vision camera " + serial() + " at " + address();
}

}  // namespace hairrig
