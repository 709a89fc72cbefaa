#include "sim_hw/sim_gpio.h"

#include <chrono>
#include <condition_variable>
#include <deque>

#include "drivers/camera_support.h"

namespace hairrig {

namespace {}  // namespace

struct SimGpioProvider::Line {
  bool level = false;
  bool active_low = false;
  bool output = false;
  std::string consumer;
  std::vector<SimGpioTransition> transitions;
  std::deque<GpioEdge> events;  // pending, for an input's requester
  std::condition_variable event_cv;
  Status broken;  // BreakLine: what every read returns from then on
};

struct SimGpioProvider::Chip {
  std::string label;
  std::string name;
  std::vector<std::unique_ptr<Line>> lines;
};

// The requester's handle on a claimed line: releases it when destroyed.
class SimGpioHandle : public GpioOutputLine, public GpioInputLine {
 public:
  SimGpioHandle(std::shared_ptr<SimGpioProvider> provider, SimGpioProvider::Line* line)
      : provider_(std::move(provider)), line_(line) {}
  ~SimGpioHandle() override { provider_->Release(line_); }

  Status Set(bool active) override {
    std::lock_guard<std::mutex> lock(provider_->mutex_);
    const bool level = active != line_->active_low;
    if (level != line_->level) {
      line_->level = level;
      line_->transitions.push_back({level, SteadyNowNs()});
    }
    return Status::Ok();
  }
  Result<bool> Get() override {
    std::lock_guard<std::mutex> lock(provider_->mutex_);
    if (!line_->broken.ok()) return line_->broken;
    return line_->level != line_->active_low;
  }
  Result<std::optional<GpioEdge>> WaitEdge(std::chrono::milliseconds timeout) override {
    std::unique_lock<std::mutex> lock(provider_->mutex_);
    if (!line_->event_cv.wait_for(
            lock, timeout, [this] { return !line_->events.empty() || !line_->broken.ok(); })) {
      return std::optional<GpioEdge>();
    }
    if (!line_->broken.ok()) return line_->broken;
    const GpioEdge edge = line_->events.front();
    line_->events.pop_front();
    return std::optional<GpioEdge>(edge);
  }

 private:
  std::shared_ptr<SimGpioProvider> provider_;
  SimGpioProvider::Line* line_;
};

SimGpioProvider::SimGpioProvider() = default;
SimGpioProvider::~SimGpioProvider() = default;

void SimGpioProvider::AddChip(const std::string& label, int lines) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto chip = std::make_unique<Chip>();
  chip->label = label;
  chip->name = "gpiochip" + std::to_string(chips_.size());
  for (int i = 0; i < lines; ++i) chip->lines.push_back(std::make_unique<Line>());
  chips_.push_back(std::move(chip));
}

Result<SimGpioProvider::Line*> SimGpioProvider::Claim(const GpioLineRequest& r, bool output) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string known;
  for (const auto& chip : chips_) {
    if (chip->label != r.chip && chip->name != r.chip) {
      known += (known.empty() ? "" : ", ") + chip->name + " [" + chip->label + "]";
      continue;
    }
    if (r.offset < 0 || r.offset >= static_cast<int>(chip->lines.size())) {
      return OutOfRange(r.Describe() + ": the chip has " + std::to_string(chip->lines.size()) +
                        " lines");
    }
    Line& line = *chip->lines[static_cast<size_t>(r.offset)];
    if (!line.consumer.empty()) {
      return Unavailable(r.Describe() + " cannot be requested: held by '" + line.consumer +
                         "'; check that no other program or device uses the line");
    }
    line.consumer = r.consumer.empty() ? "?" : r.consumer;
    line.active_low = r.active_low;
    line.output = output;
    line.events.clear();
    if (output) {
      const bool level = r.initial_active != r.active_low;
      if (level != line.level) line.transitions.push_back({level, SteadyNowNs()});
      line.level = level;
    }
    return &line;
  }
  return NotFound("GPIO chip '" + r.chip +
                  "' not found (simulated chips: " + (known.empty() ? "none" : known) + ")");
}

void SimGpioProvider::Release(Line* line) {
  std::lock_guard<std::mutex> lock(mutex_);
  line->consumer.clear();
  line->events.clear();
}

Result<std::unique_ptr<GpioOutputLine>> SimGpioProvider::RequestOutput(const GpioLineRequest& r) {
  HR_ASSIGN_OR_RETURN(Line * line, Claim(r, true));
  return std::unique_ptr<GpioOutputLine>(std::make_unique<SimGpioHandle>(shared_from_this(), line));
}

Result<std::unique_ptr<GpioInputLine>> SimGpioProvider::RequestInput(const GpioLineRequest& r) {
  HR_ASSIGN_OR_RETURN(Line * line, Claim(r, false));
  return std::unique_ptr<GpioInputLine>(std::make_unique<SimGpioHandle>(shared_from_this(), line));
}

namespace {
template <typename Chips>
SimGpioProvider::Line* FindLine(const Chips& chips, const std::string& name, int offset) {
  for (const auto& chip : chips) {
    if ((chip->label == name || chip->name == name) && offset >= 0 &&
        offset < static_cast<int>(chip->lines.size())) {
      return chip->lines[static_cast<size_t>(offset)].get();
    }
  }
  return nullptr;
}
}  // namespace

bool SimGpioProvider::Level(const std::string& chip, int offset) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Line* line = FindLine(chips_, chip, offset);
  return line != nullptr && line->level;
}

std::vector<SimGpioTransition> SimGpioProvider::Transitions(const std::string& chip,
                                                            int offset) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Line* line = FindLine(chips_, chip, offset);
  return line != nullptr ? line->transitions : std::vector<SimGpioTransition>{};
}

std::string SimGpioProvider::Consumer(const std::string& chip, int offset) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Line* line = FindLine(chips_, chip, offset);
  return line != nullptr ? line->consumer : "";
}

Status SimGpioProvider::DriveInput(const std::string& chip, int offset, bool level) {
  std::lock_guard<std::mutex> lock(mutex_);
  Line* line = FindLine(chips_, chip, offset);
  if (line == nullptr)
    return NotFound("no simulated line " + std::to_string(offset) + " of " + chip);
  if (line->output && !line->consumer.empty()) {
    return FailedPrecondition("line " + std::to_string(offset) + " of " + chip +
                              " is an output of '" + line->consumer + "'");
  }
  if (level == line->level) return Status::Ok();
  line->level = level;
  const int64_t now = SteadyNowNs();
  line->transitions.push_back({level, now});
  if (!line->consumer.empty()) {
    line->events.push_back({level != line->active_low, now});
    line->event_cv.notify_all();
  }
  return Status::Ok();
}

Status SimGpioProvider::BreakLine(const std::string& chip, int offset, Status error) {
  if (error.ok()) return InvalidArgument("BreakLine needs the error the line's reads return");
  std::lock_guard<std::mutex> lock(mutex_);
  Line* line = FindLine(chips_, chip, offset);
  if (line == nullptr)
    return NotFound("no simulated line " + std::to_string(offset) + " of " + chip);
  line->broken = std::move(error);
  line->event_cv.notify_all();
  return Status::Ok();
}

}  // namespace hairrig
