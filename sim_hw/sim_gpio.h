// A simulated GPIO provider (drivers/gpio_provider.h) for machines without
// GPIO: chips with named labels and line counts, outputs whose physical
// transitions are recorded with timestamps (what a logic analyser would
// show), inputs driven by the test or the simulated rig (a button press),
// with edge events. Requests behave as the kernel's do: one consumer per
// line (a second request is refused, naming the holder), unknown chips and
// offsets refused. Thread-safe.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "drivers/gpio_provider.h"

namespace hairrig {

struct SimGpioTransition {
  bool level = false;  // physical level after the transition
  int64_t timestamp_ns = 0;
};

class SimGpioProvider : public GpioProvider, public std::enable_shared_from_this<SimGpioProvider> {
 public:
  SimGpioProvider();
  ~SimGpioProvider() override;
  // A chip found by `label` or by its name "gpiochipN" (N: order of adding).
  void AddChip(const std::string& label, int lines);

  std::string name() const override { return "simulated"; }
  Result<std::unique_ptr<GpioOutputLine>> RequestOutput(const GpioLineRequest& request) override;
  Result<std::unique_ptr<GpioInputLine>> RequestInput(const GpioLineRequest& request) override;

  // The physical level of a line now; false for unknown lines.
  bool Level(const std::string& chip, int offset) const;
  // Every physical transition of a line since the chip was added.
  std::vector<SimGpioTransition> Transitions(const std::string& chip, int offset) const;
  // Drives an input's physical level (a button, a door switch); an edge event
  // reaches the line's requester when the level changes.
  Status DriveInput(const std::string& chip, int offset, bool level);
  // Breaks a line as an unplugged chip or a cut cable would: its requester's
  // reads and edge waits fail with `error` (not ok) from then on.
  Status BreakLine(const std::string& chip, int offset, Status error);
  // Who holds a line ("" when free).
  std::string Consumer(const std::string& chip, int offset) const;

  struct Line;
  struct Chip;

 private:
  friend class SimGpioHandle;
  Result<Line*> Claim(const GpioLineRequest& request, bool output);
  void Release(Line* line);

  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Chip>> chips_;
};

}  // namespace hairrig
