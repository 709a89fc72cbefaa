// The `gpiod` backend: GPIO lines as LED panel power (Light), camera trigger
// outputs (TriggerLine) and safety inputs with edge events (InputLine), over
// a GpioProvider (drivers/gpio_provider.h): libgpiod on a real rig, the
// simulated provider in tests.
//
// Rig config fields, beside name, backend and serial:
//   chip: pinctrl-bcm2711   # required: label (stable across boots), name (gpiochip0), number or
//   path line: 17                # required: offset within the chip active_low: false       # true
//   when the line is asserted by pulling it low bias: as_is             # inputs: as_is | disable |
//   pull_up | pull_down
// A GPIO line has no serial number of its own: `serial` names the wired
// function (the panel's or the button's asset tag), and a line is identified
// by chip label and offset.
//
// A light is on/off (not dimmable) and is switched off when closed; a
// trigger pulse asserts the line for the requested width and blocks for it;
// an input line watches both edges on a thread of its own while open.
#pragma once

#include <memory>

#include "drivers/gpio_provider.h"
#include "drivers/registry.h"

namespace hairrig {

// Registers the `gpiod` backend of lights, trigger lines and input lines, all
// reaching their lines through `provider`.
void RegisterGpioBackends(DeviceRegistry* registry, std::shared_ptr<GpioProvider> provider);

}  // namespace hairrig
