#include "sim_hw/sim_v4l2.h"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "sim_hw/sim_devices.h"

namespace hairrig {
namespace {

constexpr int kFirstFd = 1000;
constexpr uint32_t kPage = 4096;

int Fail(int e) {
  errno = e;
  return -1;
}

void CopyText(uint8_t* out, size_t size, const char* text) {
  std::snprintf(reinterpret_cast<char*>(out), size, "%s", text);
}

// YUYV 4:2:2 of a BGR image, BT.601 limited range (Y 16-235, Cb/Cr 16-240)
// as UVC cameras send it.
void PackYuyv(const cv::Mat& bgr, uint8_t* out) {
  cv::Mat ycrcb;
  cv::cvtColor(bgr, ycrcb, cv::COLOR_BGR2YCrCb);  // full range
  auto luma = [](int y) { return static_cast<uint8_t>(16 + (y * 219 + 127) / 255); };
  auto chroma = [](int c0, int c1) {
    return static_cast<uint8_t>(128 + ((c0 + c1) / 2 - 128) * 224 / 255);
  };
  for (int y = 0; y < ycrcb.rows; ++y) {
    const cv::Vec3b* row = ycrcb.ptr<cv::Vec3b>(y);
    uint8_t* o = out + static_cast<size_t>(y) * ycrcb.cols * 2;
    for (int x = 0; x + 1 < ycrcb.cols; x += 2) {
      o[2 * x] = luma(row[x][0]);
      o[2 * x + 1] = chroma(row[x][2], row[x + 1][2]);  // Cb
      o[2 * x + 2] = luma(row[x + 1][0]);
      o[2 * x + 3] = chroma(row[x][1], row[x + 1][1]);  // Cr
    }
  }
}

struct Buffer {
  std::vector<uint8_t> memory;
  enum class State { kIdle, kQueued, kFilled } state = State::kIdle;
  WorldExposure exposure;  // latched when filled
  bool corrupt = false;    // filled while a CorruptNextFrames count was pending
  int64_t timestamp_ns = 0;
  uint32_t sequence = 0;
};

}  // namespace

class SimV4l2Device::Impl {
 public:
  Impl(std::shared_ptr<SimWorld> world, SimV4l2Options options)
      : world_(std::move(world)), options_(std::move(options)) {
    const auto& intrinsics = WorldRenderer(*world_)
                                 .scene()
                                 .cameras.at(static_cast<size_t>(options_.scene_camera))
                                 .intrinsics;
    width_ = static_cast<uint32_t>(intrinsics.width_px);
    height_ = static_cast<uint32_t>(intrinsics.height_px);
  }
  ~Impl() { StopStreaming(); }

  std::vector<std::string> ListNodes() {
    std::lock_guard<std::mutex> lock(mutex_);
    return unplugged_ ? std::vector<std::string>{} : std::vector<std::string>{options_.node};
  }
  std::string UsbSerial(const std::string& node) {
    return node == options_.node ? options_.serial : "";
  }

  int Open(const std::string& path) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (unplugged_ || path != options_.node) return Fail(ENOENT);
    const int fd = next_fd_++;
    open_fds_.insert({fd, true});
    return fd;
  }
  int Close(int fd) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!open_fds_.erase(fd)) return Fail(EBADF);
    if (open_fds_.empty()) {
      lock.unlock();
      StopStreaming();
      lock.lock();
      buffers_.clear();
    }
    return 0;
  }

  int Ioctl(int fd, unsigned long request, void* arg) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!open_fds_.count(fd)) return Fail(EBADF);
    if (unplugged_) return Fail(ENODEV);
    switch (request) {
      case VIDIOC_QUERYCAP:
        return QueryCap(static_cast<v4l2_capability*>(arg));
      case VIDIOC_ENUM_FMT:
        return EnumFormat(static_cast<v4l2_fmtdesc*>(arg));
      case VIDIOC_S_FMT:
      case VIDIOC_G_FMT:
        return SetFormat(static_cast<v4l2_format*>(arg), request == VIDIOC_S_FMT);
      case VIDIOC_REQBUFS:
        return RequestBuffers(static_cast<v4l2_requestbuffers*>(arg));
      case VIDIOC_QUERYBUF:
        return QueryBuffer(static_cast<v4l2_buffer*>(arg));
      case VIDIOC_QBUF:
        return Queue(static_cast<v4l2_buffer*>(arg));
      case VIDIOC_DQBUF:
        return Dequeue(static_cast<v4l2_buffer*>(arg), lock);
      case VIDIOC_STREAMON:
        lock.unlock();
        StartStreaming();
        return 0;
      case VIDIOC_STREAMOFF:
        lock.unlock();
        StopStreaming();
        return 0;
      case VIDIOC_QUERYCTRL:
        return QueryControl(static_cast<v4l2_queryctrl*>(arg));
      case VIDIOC_S_CTRL:
        return SetControl(static_cast<v4l2_control*>(arg));
      case VIDIOC_G_CTRL:
        return GetControl(static_cast<v4l2_control*>(arg));
      default:
        return Fail(ENOTTY);
    }
  }

  void* Mmap(size_t length, int fd, int64_t offset) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!open_fds_.count(fd) || unplugged_) {
      errno = ENODEV;
      return MAP_FAILED;
    }
    const size_t index = static_cast<size_t>(offset / kPage);
    if (index >= buffers_.size() || length > buffers_[index].memory.size()) {
      errno = EINVAL;
      return MAP_FAILED;
    }
    return buffers_[index].memory.data();
  }

  int PollReadable(int fd, int timeout_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!open_fds_.count(fd)) return Fail(EBADF);
    const bool ready = cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [this] {
      if (unplugged_) return true;
      for (const Buffer& b : buffers_) {
        if (b.state == Buffer::State::kFilled) return true;
      }
      return false;
    });
    if (unplugged_) return Fail(ENODEV);
    return ready ? 1 : 0;
  }

  void Unplug() {
    std::lock_guard<std::mutex> lock(mutex_);
    unplugged_ = true;
    cv_.notify_all();
  }
  void Replug() {
    StopStreaming();
    std::lock_guard<std::mutex> lock(mutex_);
    unplugged_ = false;
    open_fds_.clear();
    buffers_.clear();
  }
  void CorruptNextFrames(int count) {
    std::lock_guard<std::mutex> lock(mutex_);
    corrupt_left_ += count;
  }
  bool WaitUntilQueuedBuffersFilled(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return cv_.wait_for(lock, timeout, [this] {
      bool filled = false;
      for (const Buffer& b : buffers_) {
        if (b.state == Buffer::State::kQueued) return false;
        filled = filled || b.state == Buffer::State::kFilled;
      }
      return filled;
    });
  }
  int delivered() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return delivered_;
  }
  int dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }

 private:
  int QueryCap(v4l2_capability* caps) {
    *caps = {};
    CopyText(caps->driver, sizeof(caps->driver), "uvcvideo");
    CopyText(caps->card, sizeof(caps->card), "Hairrig Simulated UVC");
    CopyText(caps->bus_info, sizeof(caps->bus_info), "usb-sim-1");
    caps->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
    caps->capabilities = caps->device_caps | V4L2_CAP_DEVICE_CAPS;
    return 0;
  }

  int EnumFormat(v4l2_fmtdesc* d) {
    static const uint32_t kFormats[] = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV};
    if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= 2) return Fail(EINVAL);
    d->pixelformat = kFormats[d->index];
    CopyText(d->description, sizeof(d->description), d->index == 0 ? "Motion-JPEG" : "YUYV 4:2:2");
    return 0;
  }

  int SetFormat(v4l2_format* f, bool set) {
    if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return Fail(EINVAL);
    if (set) {
      if (streaming_) return Fail(EBUSY);
      fourcc_ =
          f->fmt.pix.pixelformat == V4L2_PIX_FMT_YUYV ? V4L2_PIX_FMT_YUYV : V4L2_PIX_FMT_MJPEG;
    }
    f->fmt.pix.width = width_;  // the only size it has, whatever was asked
    f->fmt.pix.height = height_;
    f->fmt.pix.pixelformat = fourcc_;
    f->fmt.pix.field = V4L2_FIELD_NONE;
    f->fmt.pix.bytesperline = fourcc_ == V4L2_PIX_FMT_YUYV ? width_ * 2 : 0;
    f->fmt.pix.sizeimage = width_ * height_ * 2;
    return 0;
  }

  int RequestBuffers(v4l2_requestbuffers* r) {
    if (r->memory != V4L2_MEMORY_MMAP) return Fail(EINVAL);
    if (streaming_) return Fail(EBUSY);
    buffers_.assign(std::min<uint32_t>(r->count, 8), Buffer{});
    for (Buffer& b : buffers_) b.memory.assign(static_cast<size_t>(width_) * height_ * 2, 0);
    r->count = static_cast<uint32_t>(buffers_.size());
    return 0;
  }

  Buffer* Find(uint32_t index) { return index < buffers_.size() ? &buffers_[index] : nullptr; }

  int QueryBuffer(v4l2_buffer* b) {
    Buffer* buffer = Find(b->index);
    if (!buffer) return Fail(EINVAL);
    b->length = static_cast<uint32_t>(buffer->memory.size());
    b->m.offset = b->index * kPage;
    return 0;
  }

  int Queue(v4l2_buffer* b) {
    Buffer* buffer = Find(b->index);
    if (!buffer || buffer->state == Buffer::State::kQueued) return Fail(EINVAL);
    buffer->state = Buffer::State::kQueued;
    return 0;
  }

  // The oldest filled buffer, rendered now from the world latched at its timestamp.
  int Dequeue(v4l2_buffer* b, std::unique_lock<std::mutex>& lock) {
    Buffer* oldest = nullptr;
    uint32_t index = 0;
    for (uint32_t i = 0; i < buffers_.size(); ++i) {
      Buffer& candidate = buffers_[i];
      if (candidate.state != Buffer::State::kFilled) continue;
      if (!oldest || candidate.sequence < oldest->sequence) {
        oldest = &candidate;
        index = i;
      }
    }
    if (!oldest) return Fail(EAGAIN);
    oldest->state = Buffer::State::kIdle;
    const WorldExposure exposure = oldest->exposure;
    const bool corrupt = oldest->corrupt;
    const uint32_t fourcc = fourcc_;
    const uint32_t sequence = oldest->sequence;
    uint8_t* memory = oldest->memory.data();
    const size_t capacity = oldest->memory.size();
    lock.unlock();  // rendering takes a while; the buffer is ours (idle) meanwhile
    auto image = RenderWorldExposure(*world_, options_.scene_camera, exposure, 0.02, 0,
                                     FrameNoiseSeed(*world_, options_.serial, sequence));
    uint32_t used = 0;
    if (image.ok() && fourcc == V4L2_PIX_FMT_YUYV) {
      PackYuyv(*image, memory);
      used = width_ * height_ * 2;
    } else if (image.ok()) {
      std::vector<uint8_t> jpeg;
      if (!cv::imencode(".jpg", *image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}))
        jpeg.clear();  // delivered empty: corrupt
      // A corrupt frame is cut short, as when the USB transfer loses its tail.
      used = static_cast<uint32_t>(std::min(corrupt ? size_t{64} : jpeg.size(), capacity));
      std::memcpy(memory, jpeg.data(), used);
    }
    lock.lock();
    ++delivered_;
    b->index = index;
    b->bytesused = used;
    b->sequence = sequence;
    b->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    b->timestamp.tv_sec = static_cast<time_t>(oldest->timestamp_ns / 1000000000);
    b->timestamp.tv_usec = static_cast<suseconds_t>((oldest->timestamp_ns % 1000000000) / 1000);
    return 0;
  }

  int QueryControl(v4l2_queryctrl* q) {
    const auto it = kControls().find(q->id);
    if (it == kControls().end()) return Fail(EINVAL);
    q->minimum = it->second.first;
    q->maximum = it->second.second;
    q->step = 1;
    q->flags = 0;
    return 0;
  }
  int SetControl(v4l2_control* c) {
    const auto it = kControls().find(c->id);
    if (it == kControls().end()) return Fail(EINVAL);
    if (c->value < it->second.first || c->value > it->second.second) return Fail(ERANGE);
    controls_[c->id] = c->value;
    return 0;
  }
  int GetControl(v4l2_control* c) {
    if (!kControls().count(c->id)) return Fail(EINVAL);
    c->value = controls_[c->id];
    return 0;
  }
  static const std::map<uint32_t, std::pair<int, int>>& kControls() {
    static const std::map<uint32_t, std::pair<int, int>> controls = {
        {V4L2_CID_EXPOSURE_AUTO, {0, 3}},
        {V4L2_CID_EXPOSURE_ABSOLUTE, {1, 10000}},
        {V4L2_CID_GAIN, {0, 255}}};
    return controls;
  }

  void StartStreaming() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (streaming_) return;
    streaming_ = true;
    producer_ = std::thread([this] { Produce(); });
  }
  void StopStreaming() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!streaming_) return;
      streaming_ = false;
      cv_.notify_all();
    }
    if (producer_.joinable()) producer_.join();
    std::lock_guard<std::mutex> lock(mutex_);
    for (Buffer& b : buffers_) b.state = Buffer::State::kIdle;
  }

  // Every frame period: the oldest queued buffer takes the world as it is now.
  void Produce() {
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(WorldTimeScale(*world_) / options_.fps));
    auto next = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(mutex_);
    while (streaming_) {
      next += period;
      if (cv_.wait_until(lock, next, [this] { return !streaming_; })) break;
      Buffer* target = nullptr;
      for (Buffer& b : buffers_) {
        if (b.state == Buffer::State::kQueued) {
          target = &b;
          break;
        }
      }
      if (!target) {
        ++dropped_;
        continue;
      }
      target->exposure = ExposeWorldNow(*world_);
      target->timestamp_ns = target->exposure.trigger_ns;
      target->sequence = next_sequence_++;
      target->corrupt = corrupt_left_ > 0;
      if (target->corrupt) --corrupt_left_;
      target->state = Buffer::State::kFilled;
      cv_.notify_all();
    }
  }

  std::shared_ptr<SimWorld> world_;
  SimV4l2Options options_;
  uint32_t width_ = 0;
  uint32_t height_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::map<int, bool> open_fds_;
  int next_fd_ = kFirstFd;
  bool unplugged_ = false;
  uint32_t fourcc_ = V4L2_PIX_FMT_MJPEG;
  std::vector<Buffer> buffers_;
  bool streaming_ = false;
  std::thread producer_;
  uint32_t next_sequence_ = 0;
  std::map<uint32_t, int> controls_ = {{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY},
                                       {V4L2_CID_EXPOSURE_ABSOLUTE, 200},
                                       {V4L2_CID_GAIN, 0}};
  int corrupt_left_ = 0;
  int delivered_ = 0;
  int dropped_ = 0;
};

Status SimV4l2Options::Check() const {
  if (scene_camera < 0) {
    return InvalidArgument("scene_camera must be 0 or more, got " + std::to_string(scene_camera));
  }
  if (node.empty()) return InvalidArgument("node (the device path) is required");
  if (!(fps > 0) || !std::isfinite(fps)) return InvalidArgument("fps must be finite and positive");
  return Status::Ok();
}

SimV4l2Device::SimV4l2Device(std::shared_ptr<SimWorld> world, SimV4l2Options options)
    : impl_(std::make_unique<Impl>(std::move(world), std::move(options))) {}
SimV4l2Device::~SimV4l2Device() = default;
std::vector<std::string> SimV4l2Device::ListNodes() { return impl_->ListNodes(); }
std::string SimV4l2Device::UsbSerial(const std::string& node) { return impl_->UsbSerial(node); }
int SimV4l2Device::Open(const std::string& path, int) { return impl_->Open(path); }
int SimV4l2Device::Close(int fd) { return impl_->Close(fd); }
int SimV4l2Device::Ioctl(int fd, unsigned long request, void* arg) {
  return impl_->Ioctl(fd, request, arg);
}
void* SimV4l2Device::Mmap(size_t length, int, int, int fd, int64_t offset) {
  return impl_->Mmap(length, fd, offset);
}
int SimV4l2Device::Munmap(void*, size_t) { return 0; }
int SimV4l2Device::PollReadable(int fd, int timeout_ms) {
  return impl_->PollReadable(fd, timeout_ms);
}
void SimV4l2Device::Unplug() { impl_->Unplug(); }
void SimV4l2Device::Replug() { impl_->Replug(); }
void SimV4l2Device::CorruptNextFrames(int count) { impl_->CorruptNextFrames(count); }
bool SimV4l2Device::WaitUntilQueuedBuffersFilled(std::chrono::milliseconds timeout) {
  return impl_->WaitUntilQueuedBuffersFilled(timeout);
}
int SimV4l2Device::frames_delivered() const { return impl_->delivered(); }
int SimV4l2Device::frames_dropped() const { return impl_->dropped(); }

}  // namespace hairrig
