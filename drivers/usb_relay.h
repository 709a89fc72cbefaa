// The `usbrelay` light backend: an LED panel's power on one channel of a HID
// USB relay board (drivers/usb_relay_protocol.h), through a bus interface
// (UsbRelayBus): libusb, or one the backend's hook supplies.
//
// Config fields (devices.lights[i]):
//   serial:  the panel's asset tag (a relay channel has no serial of its own)
//   board:   the board's id (5 characters, read from the board; `hairrig
//            devices --discover` prints it), so the board is found whichever
//            USB socket it is in; several lights can share a board
//   channel: 1..N, the relay the panel is wired to
//   bus:     usb (default: libusb) or the name of a bus the backend's hook
//            supplies; the hook may read further fields (`hook_fields`)
//
// SetOn switches the channel and reads the board's state back: a channel that
// did not follow is a DeviceFault (a welded contact, a board that lost power).
// A board that is gone faults the light (Unavailable); Open finds it again by
// id. Panels are switched off when the light is closed.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/light.h"
#include "drivers/registry.h"
#include "drivers/usb_relay_protocol.h"

namespace hairrig {

class UsbRelayBus {
 public:
  struct Board {
    std::string port_path;  // "1-2.3": bus and port chain
    std::string product;    // "USBRelay2"
  };
  virtual ~UsbRelayBus() = default;
  // The relay boards present (16c0:05df devices named USBRelayN).
  virtual Result<std::vector<Board>> List() = 0;
  virtual Status SetReport(const std::string& port_path, const UsbRelayReport& report) = 0;
  virtual Result<UsbRelayReport> GetReport(const std::string& port_path) = 0;
};

// libusb: each exchange opens the board, detaches the kernel's usbhid driver
// from interface 0 if bound, claims it, transfers, and releases it.
std::shared_ptr<UsbRelayBus> MakeLibusbRelayBus();

// The channel count a product string names ("USBRelay2" -> 2), or 0.
int UsbRelayChannels(const std::string& product);

inline constexpr char kLibusbRelayBusName[] = "usb";

struct UsbRelayLightOptions {
  std::string board_id;
  int channel = 1;
  std::string bus_name = kLibusbRelayBusName;  // the config's `bus`
  // The boards' bus. Null: libusb, for bus_name "usb"; any other bus_name
  // needs a hook that sets it.
  std::shared_ptr<UsbRelayBus> bus;

  // InvalidArgument naming the config field (board, channel, bus) for a
  // value out of the range ParseUsbRelayLightOptions accepts.
  Status Check() const;
};
// `hook_fields`: further fields of the device's map that the backend's hook
// reads (allowed here, not read).
Result<UsbRelayLightOptions> ParseUsbRelayLightOptions(
    const ConfigNode& device, const std::vector<std::string>& hook_fields = {});
std::unique_ptr<Light> MakeUsbRelayLight(const DeviceInfo& info, UsbRelayLightOptions options);

// Runs before each light is built; may set `bus` for the buses it supplies
// and fail (the light is not built).
using UsbRelayOptionsHook = std::function<Status(const DeviceConfig&, UsbRelayLightOptions*)>;
// A light whose bus_name is neither "usb" nor given a bus by `hook` is refused
// (InvalidArgument at the device's file:line).
void RegisterUsbRelayBackend(DeviceRegistry* registry, UsbRelayOptionsHook hook = nullptr,
                             std::vector<std::string> hook_fields = {});

}  // namespace hairrig
