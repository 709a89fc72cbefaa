// GPIO lines behind an injectable provider: the libgpiod character-device
// provider for real chips, or a simulated one (sim_hw/sim_gpio.h) for tests
// and machines without GPIO. The `gpiod` devices (drivers/gpio_devices.h) are
// written against this interface only.
//
// Values are logical: `active` is true when the line is asserted; a line
// requested active-low is physically low when active (the provider inverts).
// Failures are Status values naming the chip and line: an unknown chip
// (NotFound, listing the chips there are), an offset beyond the chip
// (OutOfRange), a line held by another consumer (Unavailable).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

enum class GpioBias { kAsIs, kDisable, kPullUp, kPullDown };

struct GpioLineRequest {
  std::string chip;      // label ("pinctrl-bcm2711"), name ("gpiochip0"), number or /dev path
  int offset = 0;        // line offset within the chip
  std::string consumer;  // shown by gpioinfo: the device's name
  bool active_low = false;
  GpioBias bias = GpioBias::kAsIs;
  bool initial_active = false;  // outputs only
  // "line 17 of gpiochip0"
  std::string Describe() const;
};

struct GpioEdge {
  bool became_active =
      true;                  // the logical value went to active (active-low lines: a falling level)
  int64_t timestamp_ns = 0;  // CLOCK_MONOTONIC (libgpiod) or steady_clock (simulated)
};

class GpioOutputLine {
 public:
  virtual ~GpioOutputLine() = default;
  virtual Status Set(bool active) = 0;
};

class GpioInputLine {
 public:
  virtual ~GpioInputLine() = default;
  virtual Result<bool> Get() = 0;  // active now
  // The next edge, or nullopt when none came within `timeout`.
  virtual Result<std::optional<GpioEdge>> WaitEdge(std::chrono::milliseconds timeout) = 0;
};

class GpioProvider {
 public:
  virtual ~GpioProvider() = default;
  virtual std::string name() const = 0;  // "libgpiod", "simulated"
  virtual Result<std::unique_ptr<GpioOutputLine>> RequestOutput(const GpioLineRequest& request) = 0;
  // An input with edge events on both edges.
  virtual Result<std::unique_ptr<GpioInputLine>> RequestInput(const GpioLineRequest& request) = 0;
};

// The real provider: the kernel's GPIO character devices through libgpiod 1.6.
std::shared_ptr<GpioProvider> MakeLibgpiodProvider();

// A GPIO chip of this machine's kernel (for `hairrig devices --discover`).
struct GpioChipInfo {
  std::string name;   // "gpiochip0"
  std::string label;  // "pinctrl-bcm2711": what a config's `chip` should name
  int lines = 0;
};
// The chips libgpiod finds under /dev; empty where the kernel has no GPIO.
std::vector<GpioChipInfo> ListGpioChips();

}  // namespace hairrig
