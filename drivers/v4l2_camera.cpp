#include "drivers/v4l2_camera.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "drivers/uvc_discovery.h"

namespace hairrig {
namespace {

std::string FourCcText(uint32_t f) {
  return {static_cast<char>(f & 0xff), static_cast<char>((f >> 8) & 0xff),
          static_cast<char>((f >> 16) & 0xff), static_cast<char>((f >> 24) & 0xff)};
}

int64_t TimevalNs(const timeval& t) {
  return static_cast<int64_t>(t.tv_sec) * 1000000000 + t.tv_usec * 1000;
}

bool GoneErrno(int e) { return e == ENODEV || e == EIO || e == ENXIO || e == EBADF; }

struct MappedBuffer {
  void* start = MAP_FAILED;
  size_t length = 0;
};

class V4l2Camera : public Camera {
 public:
  V4l2Camera(DeviceInfo info, V4l2CameraOptions options)
      : Camera(std::move(info)), options_(std::move(options)) {
    if (!options_.io) options_.io = SystemV4l2Io();
  }
  ~V4l2Camera() override { (void)V4l2Camera::DoClose(); }

  double time_scale() const override { return options_.nominal.time_scale; }

  CameraCapabilities capabilities() const override {
    return {.width_px = options_.nominal.width_px,
            .height_px = options_.nominal.height_px,
            .formats = {PixelFormat::kRgb8, PixelFormat::kBgr8, PixelFormat::kMono8},
            .min_exposure_s = 1e-4,
            .max_exposure_s = 1.0,
            .line_trigger = false,
            .readout_s = options_.nominal.readout_s,
            .download_s = options_.nominal.download_s};
  }

 protected:
  Status DoOpen() override {
    (void)Close();
    std::lock_guard<std::mutex> lock(mutex_);
    HR_ASSIGN_OR_RETURN(path_, FindNode());
    fd_ = io().Open(path_, O_RDWR | O_NONBLOCK);
    if (fd_ < 0) return Fault(Unavailable(path_ + ": cannot open (" + std::strerror(errno) + ")"));
    Status s = NegotiateFormat();
    if (s.ok()) s = MapBuffers();
    if (!s.ok()) {
      ReleaseLocked();
      return Fault(s);
    }
    SetState(DeviceState::kReady);
    return Status::Ok();
  }

  Status DoClose() override {
    std::lock_guard<std::mutex> lock(mutex_);
    ReleaseLocked();
    return Status::Ok();
  }

  Status DoHealthCheck() override {
    std::lock_guard<std::mutex> lock(mutex_);
    v4l2_capability caps{};
    if (io().Ioctl(fd_, VIDIOC_QUERYCAP, &caps) != 0) return GoneLocked("VIDIOC_QUERYCAP");
    return Status::Ok();
  }

  Status DoConfigure(const CaptureSettings& s) override {
    HR_RETURN_IF_ERROR(CheckExposure(*this, capabilities(), s.exposure_s));
    if (s.trigger == TriggerSource::kLine) {
      return OutOfRange(Describe() +
                        ": a UVC camera has no trigger input; leave its trigger_line out");
    }
    if (s.format != PixelFormat::kRgb8 && s.format != PixelFormat::kBgr8 &&
        s.format != PixelFormat::kMono8) {
      return OutOfRange(Describe() + ": delivers rgb8, bgr8 or mono8");
    }
    std::lock_guard<std::mutex> lock(mutex_);
    HR_RETURN_IF_ERROR(
        SetControl(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "auto exposure off", true));
    HR_RETURN_IF_ERROR(SetControl(V4L2_CID_EXPOSURE_ABSOLUTE,
                                  static_cast<int>(s.exposure_s * 1e4 + 0.5), "exposure", true));
    HR_RETURN_IF_ERROR(
        SetControl(V4L2_CID_GAIN, static_cast<int>(s.gain_db + 0.5), "gain", s.gain_db != 0));
    settings_ = s;
    return Status::Ok();
  }

  Status DoArm() override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (size_t i = 0; i < buffers_.size(); ++i) {
      v4l2_buffer b = BufferRequest(static_cast<uint32_t>(i));
      if (io().Ioctl(fd_, VIDIOC_QBUF, &b) != 0) return GoneLocked("VIDIOC_QBUF");
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (io().Ioctl(fd_, VIDIOC_STREAMON, &type) != 0) return GoneLocked("VIDIOC_STREAMON");
    streaming_ = true;
    sequence_ = 0;
    pending_triggers_ns_.clear();
    return Status::Ok();
  }

  Status DoDisarm() override {
    std::lock_guard<std::mutex> lock(mutex_);
    StreamOffLocked();
    return Status::Ok();
  }

  Status DoSoftwareTrigger() override {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_triggers_ns_.push_back(SteadyNowNs());
    return Status::Ok();
  }

  // UVC cameras have no trigger input: Configure refuses TriggerSource::kLine.
  void DoLineTriggerSent(int64_t) override {}

  Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      int64_t trigger_ns = 0;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!pending_triggers_ns_.empty()) trigger_ns = pending_triggers_ns_.front();
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (trigger_ns == 0 || left.count() <= 0) {
        return Timeout(
            Describe() + ": no frame within " + std::to_string(timeout.count()) + " ms" +
            (trigger_ns == 0 ? " (a UVC camera delivers frames after SoftwareTrigger)" : ""));
      }
      const int ready = io().PollReadable(fd_, static_cast<int>(left.count()));
      std::lock_guard<std::mutex> lock(mutex_);
      if (ready < 0) return GoneLocked("poll");
      if (ready == 0) continue;
      v4l2_buffer b = BufferRequest(0);
      if (io().Ioctl(fd_, VIDIOC_DQBUF, &b) != 0) {
        if (errno == EAGAIN) continue;
        return GoneLocked("VIDIOC_DQBUF");
      }
      // A frame exposed before the trigger is the camera's stream running on: skip it.
      const bool before_trigger = TimevalNs(b.timestamp) < trigger_ns;
      Result<Frame> frame =
          before_trigger ? Result<Frame>(Internal("skipped")) : DecodeLocked(b, trigger_ns);
      if (io().Ioctl(fd_, VIDIOC_QBUF, &b) != 0) return GoneLocked("VIDIOC_QBUF");
      if (before_trigger) continue;
      pending_triggers_ns_.pop_front();
      return frame;
    }
  }

 private:
  V4l2Io& io() { return *options_.io; }

  // The node whose USB serial is the device's: the configured one, or the first found.
  Result<std::string> FindNode() {
    std::string seen;
    for (const V4l2Detected& d : DetectV4l2Cameras(io())) {
      if (!d.error.empty()) {
        seen += (seen.empty() ? "" : "; ") + d.path + ": " + d.error;
        continue;
      }
      if ((options_.device.empty() || d.path == options_.device) && d.serial == info().serial)
        return d.path;
      seen +=
          (seen.empty() ? "" : "; ") + d.path + " (" + d.card + ") has serial '" + d.serial + "'";
    }
    return Fault(Unavailable(
        "not found" + (seen.empty() ? std::string(" (no /dev/video* capture node)") : ": " + seen) +
        "; check its cable, or `v4l2-ctl --list-devices`"));
  }

  Status NegotiateFormat() {
    bool mjpeg = false, yuyv = false;
    for (uint32_t i = 0;; ++i) {
      v4l2_fmtdesc d{};
      d.index = i;
      d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (io().Ioctl(fd_, VIDIOC_ENUM_FMT, &d) != 0) break;
      mjpeg = mjpeg || d.pixelformat == V4L2_PIX_FMT_MJPEG;
      yuyv = yuyv || d.pixelformat == V4L2_PIX_FMT_YUYV;
    }
    const bool want_mjpeg =
        options_.wire == V4l2Wire::kMjpeg || (options_.wire == V4l2Wire::kAuto && mjpeg);
    if ((want_mjpeg && !mjpeg) || (!want_mjpeg && !yuyv)) {
      return OutOfRange(path_ + ": does not offer " + (want_mjpeg ? "MJPEG" : "YUYV") +
                        " (it offers" + (mjpeg ? " MJPEG" : "") + (yuyv ? " YUYV" : "") + ")");
    }
    v4l2_format f{};
    f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    f.fmt.pix.width = static_cast<uint32_t>(options_.nominal.width_px);
    f.fmt.pix.height = static_cast<uint32_t>(options_.nominal.height_px);
    f.fmt.pix.pixelformat = want_mjpeg ? V4L2_PIX_FMT_MJPEG : V4L2_PIX_FMT_YUYV;
    f.fmt.pix.field = V4L2_FIELD_NONE;
    if (io().Ioctl(fd_, VIDIOC_S_FMT, &f) != 0)
      return IoError(path_ + ": VIDIOC_S_FMT: " + std::strerror(errno));
    if (static_cast<int>(f.fmt.pix.width) != options_.nominal.width_px ||
        static_cast<int>(f.fmt.pix.height) != options_.nominal.height_px) {
      return OutOfRange(path_ + ": offers " + std::to_string(f.fmt.pix.width) + "x" +
                        std::to_string(f.fmt.pix.height) + " " + FourCcText(f.fmt.pix.pixelformat) +
                        " instead of the configured " + std::to_string(options_.nominal.width_px) +
                        "x" + std::to_string(options_.nominal.height_px) +
                        " (`v4l2-ctl --list-formats-ext` lists its sizes)");
    }
    fourcc_ = f.fmt.pix.pixelformat;
    bytes_per_line_ = f.fmt.pix.bytesperline ? f.fmt.pix.bytesperline : f.fmt.pix.width * 2;
    return Status::Ok();
  }

  v4l2_buffer BufferRequest(uint32_t index) const {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    return b;
  }

  Status MapBuffers() {
    v4l2_requestbuffers request{};
    request.count = static_cast<uint32_t>(options_.buffers);
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    if (io().Ioctl(fd_, VIDIOC_REQBUFS, &request) != 0 || request.count == 0) {
      return IoError(path_ +
                     ": VIDIOC_REQBUFS (mmap streaming not supported?): " + std::strerror(errno));
    }
    for (uint32_t i = 0; i < request.count; ++i) {
      v4l2_buffer b = BufferRequest(i);
      if (io().Ioctl(fd_, VIDIOC_QUERYBUF, &b) != 0)
        return IoError(path_ + ": VIDIOC_QUERYBUF: " + std::strerror(errno));
      MappedBuffer m;
      m.length = b.length;
      m.start = io().Mmap(b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (m.start == MAP_FAILED) return IoError(path_ + ": mmap: " + std::strerror(errno));
      buffers_.push_back(m);
    }
    return Status::Ok();
  }

  // Sets a control; a missing control is an error only when `required`.
  Status SetControl(uint32_t id, int value, const char* what, bool required) {
    v4l2_queryctrl query{};
    query.id = id;
    if (io().Ioctl(fd_, VIDIOC_QUERYCTRL, &query) != 0 || (query.flags & V4L2_CTRL_FLAG_DISABLED)) {
      if (!required) return Status::Ok();
      return OutOfRange(Describe() + ": the camera has no " + what + " control");
    }
    if (value < query.minimum || value > query.maximum) {
      return OutOfRange(Describe() + ": " + what + " " + std::to_string(value) +
                        " outside the camera's " + std::to_string(query.minimum) + " - " +
                        std::to_string(query.maximum));
    }
    v4l2_control control{id, value};
    if (io().Ioctl(fd_, VIDIOC_S_CTRL, &control) != 0) {
      return GoneErrno(errno)
                 ? GoneLocked("VIDIOC_S_CTRL")
                 : IoError(Describe() + ": setting " + what + ": " + std::strerror(errno));
    }
    return Status::Ok();
  }

  Result<Frame> DecodeLocked(const v4l2_buffer& b, int64_t trigger_ns) {
    const auto* data = static_cast<const uint8_t*>(buffers_.at(b.index).start);
    const int w = options_.nominal.width_px, h = options_.nominal.height_px;
    cv::Mat bgr;
    if (fourcc_ == V4L2_PIX_FMT_MJPEG) {
      bgr = cv::imdecode(
          cv::Mat(1, static_cast<int>(b.bytesused), CV_8UC1, const_cast<uint8_t*>(data)),
          cv::IMREAD_COLOR);
      if (bgr.empty() || bgr.cols != w || bgr.rows != h) {
        return CorruptData(Describe() + ": an MJPEG frame of " + std::to_string(b.bytesused) +
                           " bytes does not decode to " + std::to_string(w) + "x" +
                           std::to_string(h));
      }
    } else {
      if (b.bytesused < static_cast<uint32_t>(bytes_per_line_ * h)) {
        return CorruptData(Describe() + ": a YUYV frame of " + std::to_string(b.bytesused) +
                           " bytes is short");
      }
      cv::cvtColor(
          cv::Mat(h, w, CV_8UC2, const_cast<uint8_t*>(data), static_cast<size_t>(bytes_per_line_)),
          bgr, cv::COLOR_YUV2BGR_YUYV);
    }
    cv::Mat out;
    switch (settings_.format) {
      case PixelFormat::kRgb8:
        cv::cvtColor(bgr, out, cv::COLOR_BGR2RGB);
        break;
      case PixelFormat::kMono8:
        cv::cvtColor(bgr, out, cv::COLOR_BGR2GRAY);
        break;
      default:
        out = bgr;
        break;
    }
    Frame f;
    f.camera_serial = info().serial;
    f.sequence = sequence_++;
    f.width_px = w;
    f.height_px = h;
    f.format = settings_.format;
    f.data.assign(out.datastart, out.dataend);
    f.exposure_s = settings_.exposure_s;
    f.gain_db = settings_.gain_db;
    f.trigger_time_ns = trigger_ns;
    f.received_time_ns = SteadyNowNs();
    return f;
  }

  Status GoneLocked(const char* call) {
    const int e = errno;
    const std::string text =
        Describe() + ": " + call + " on " + path_ + " failed (" + std::strerror(e) + ")";
    if (!GoneErrno(e)) return IoError(text);
    ReleaseLocked();
    SetState(DeviceState::kFaulted);
    return Unavailable(text + "; the camera dropped off the bus: check its cable, then reopen it");
  }

  void StreamOffLocked() {
    if (!streaming_) return;
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    io().Ioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }

  void ReleaseLocked() {
    if (fd_ < 0) return;
    StreamOffLocked();
    for (const MappedBuffer& m : buffers_) {
      if (m.start != MAP_FAILED) io().Munmap(m.start, m.length);
    }
    buffers_.clear();
    v4l2_requestbuffers none{};
    none.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    none.memory = V4L2_MEMORY_MMAP;
    io().Ioctl(fd_, VIDIOC_REQBUFS, &none);
    io().Close(fd_);
    fd_ = -1;
  }

  V4l2CameraOptions options_;
  std::mutex mutex_;
  std::string path_;
  int fd_ = -1;
  uint32_t fourcc_ = 0;
  uint32_t bytes_per_line_ = 0;
  std::vector<MappedBuffer> buffers_;
  bool streaming_ = false;
  CaptureSettings settings_;
  uint64_t sequence_ = 0;
  std::deque<int64_t> pending_triggers_ns_;
};

}  // namespace

Result<V4l2CameraOptions> ParseV4l2CameraOptions(const ConfigNode& device) {
  device.AllowOnlyKeys({"name", "backend", "serial", "device", "width_px", "height_px", "format",
                        "buffers", "readout_s", "download_s"});
  V4l2CameraOptions o;
  o.device = device.String("device", "");
  o.nominal = ReadCameraNominal(device, o.nominal);
  const std::string wire = device.Choice("format", {"auto", "mjpeg", "yuyv"}, "auto");
  o.wire = wire == "mjpeg" ? V4l2Wire::kMjpeg : wire == "yuyv" ? V4l2Wire::kYuyv : V4l2Wire::kAuto;
  o.buffers = device.Integer("buffers", o.buffers, {.min = 2, .max = 32});
  if (o.nominal.width_px <= 0 || o.nominal.height_px <= 0)
    device.Fail("width_px", "a UVC frame size must be given");
  if (!device.ok()) return device.status();
  return o;
}

Status V4l2CameraOptions::Check() const {
  HR_RETURN_IF_ERROR(nominal.Check());
  if (nominal.width_px <= 0 || nominal.height_px <= 0)
    return InvalidArgument("width_px and height_px: a UVC frame size must be given");
  if (buffers < 2 || buffers > 32)
    return InvalidArgument("buffers must lie in 2..32, got " + std::to_string(buffers));
  return Status::Ok();
}

std::unique_ptr<Camera> MakeV4l2Camera(const DeviceInfo& info, V4l2CameraOptions options) {
  return std::make_unique<V4l2Camera>(info, std::move(options));
}

void RegisterV4l2Backend(DeviceRegistry* registry, V4l2OptionsHook hook) {
  registry->AddBackend<Camera>(
      DeviceKind::kCamera, "v4l2",
      [hook](const DeviceConfig& c) -> Result<std::unique_ptr<Camera>> {
        HR_ASSIGN_OR_RETURN(V4l2CameraOptions options, ParseV4l2CameraOptions(c.node));
        if (hook) HR_RETURN_IF_ERROR(hook(c, &options));
        HR_RETURN_IF_ERROR(options.Check().WithContext("camera " + c.name));
        return MakeV4l2Camera(
            c.Info("UVC camera" + (options.device.empty() ? "" : " (" + options.device + ")")),
            std::move(options));
      });
}

}  // namespace hairrig
