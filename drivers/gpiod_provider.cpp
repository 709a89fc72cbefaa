// The libgpiod (1.6, character device) GPIO provider.
#include <gpiod.h>

#include <cerrno>
#include <cstring>
#include <ctime>

#include "drivers/gpio_provider.h"

namespace hairrig {

std::string GpioLineRequest::Describe() const {
  return "line " + std::to_string(offset) + " of " + chip;
}

namespace {

int RequestFlags(const GpioLineRequest& r) {
  int flags = r.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  switch (r.bias) {
    case GpioBias::kAsIs:
      break;
    case GpioBias::kDisable:
      flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE;
      break;
    case GpioBias::kPullUp:
      flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP;
      break;
    case GpioBias::kPullDown:
      flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN;
      break;
  }
  return flags;
}

std::string SystemError(const std::string& what) { return what + ": " + std::strerror(errno); }

// A requested line; releases it and closes its chip when destroyed.
class LibgpiodLine {
 public:
  ~LibgpiodLine() {
    if (line_ != nullptr) gpiod_line_release(line_);
    if (chip_ != nullptr) gpiod_chip_close(chip_);
  }
  Status Open(const GpioLineRequest& r) {
    chip_ = gpiod_chip_open_lookup(r.chip.c_str());
    if (chip_ == nullptr) {
      return NotFound(SystemError("GPIO chip '" + r.chip + "' not found") +
                      "; `gpiodetect` lists the chips (name, label, lines)");
    }
    if (r.offset < 0 || static_cast<unsigned>(r.offset) >= gpiod_chip_num_lines(chip_)) {
      return OutOfRange(r.Describe() + ": the chip has " +
                        std::to_string(gpiod_chip_num_lines(chip_)) + " lines");
    }
    line_ = gpiod_chip_get_line(chip_, static_cast<unsigned>(r.offset));
    if (line_ == nullptr) return IoError(SystemError(r.Describe()));
    return Status::Ok();
  }
  Status Busy(const GpioLineRequest& r) const {
    const char* holder = gpiod_line_consumer(line_);
    return Unavailable(
        SystemError(r.Describe() + " cannot be requested") +
        (holder != nullptr ? std::string(" (held by '") + holder + "')" : std::string()) +
        "; check that no other program or kernel driver uses the line");
  }
  gpiod_line* line() const { return line_; }

 private:
  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
};

class LibgpiodOutput : public GpioOutputLine {
 public:
  Status Request(const GpioLineRequest& r) {
    request_ = r;
    HR_RETURN_IF_ERROR(line_.Open(r));
    if (gpiod_line_request_output_flags(line_.line(), r.consumer.c_str(), RequestFlags(r),
                                        r.initial_active ? 1 : 0) != 0) {
      return line_.Busy(r);
    }
    return Status::Ok();
  }
  Status Set(bool active) override {
    if (gpiod_line_set_value(line_.line(), active ? 1 : 0) != 0)
      return IoError(SystemError(request_.Describe()));
    return Status::Ok();
  }

 private:
  GpioLineRequest request_;
  LibgpiodLine line_;
};

class LibgpiodInput : public GpioInputLine {
 public:
  Status Request(const GpioLineRequest& r) {
    request_ = r;
    HR_RETURN_IF_ERROR(line_.Open(r));
    if (gpiod_line_request_both_edges_events_flags(line_.line(), r.consumer.c_str(),
                                                   RequestFlags(r)) != 0) {
      return line_.Busy(r);
    }
    return Status::Ok();
  }
  Result<bool> Get() override {
    const int v = gpiod_line_get_value(line_.line());
    if (v < 0) return IoError(SystemError(request_.Describe()));
    return v == 1;
  }
  Result<std::optional<GpioEdge>> WaitEdge(std::chrono::milliseconds timeout) override {
    timespec ts{static_cast<time_t>(timeout.count() / 1000),
                static_cast<long>(timeout.count() % 1000) * 1000000L};
    const int ready = gpiod_line_event_wait(line_.line(), &ts);
    if (ready < 0) return IoError(SystemError(request_.Describe() + ": waiting for an edge"));
    if (ready == 0) return std::optional<GpioEdge>();
    gpiod_line_event event{};
    if (gpiod_line_event_read(line_.line(), &event) != 0)
      return IoError(SystemError(request_.Describe()));
    GpioEdge edge;
    edge.became_active = event.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
    edge.timestamp_ns = static_cast<int64_t>(event.ts.tv_sec) * 1000000000LL + event.ts.tv_nsec;
    return std::optional<GpioEdge>(edge);
  }

 private:
  GpioLineRequest request_;
  LibgpiodLine line_;
};

class LibgpiodProvider : public GpioProvider {
 public:
  std::string name() const override { return "libgpiod"; }
  Result<std::unique_ptr<GpioOutputLine>> RequestOutput(const GpioLineRequest& r) override {
    auto out = std::make_unique<LibgpiodOutput>();
    HR_RETURN_IF_ERROR(out->Request(r));
    return std::unique_ptr<GpioOutputLine>(std::move(out));
  }
  Result<std::unique_ptr<GpioInputLine>> RequestInput(const GpioLineRequest& r) override {
    auto in = std::make_unique<LibgpiodInput>();
    HR_RETURN_IF_ERROR(in->Request(r));
    return std::unique_ptr<GpioInputLine>(std::move(in));
  }
};

}  // namespace

std::shared_ptr<GpioProvider> MakeLibgpiodProvider() {
  return std::make_shared<LibgpiodProvider>();
}

std::vector<GpioChipInfo> ListGpioChips() {
  std::vector<GpioChipInfo> chips;
  gpiod_chip_iter* iter = gpiod_chip_iter_new();
  if (iter == nullptr) return chips;  // no /dev/gpiochip*
  for (gpiod_chip* chip = gpiod_chip_iter_next(iter); chip != nullptr;
       chip = gpiod_chip_iter_next(iter)) {
    chips.push_back({gpiod_chip_name(chip), gpiod_chip_label(chip),
                     static_cast<int>(gpiod_chip_num_lines(chip))});
  }
  gpiod_chip_iter_free(iter);
  return chips;
}

}  // namespace hairrig
