// The `usbrelay` light backend: an LED panel's power on one channel of a HID
// USB relay board (drivers/usb_relay_protocol.h), through a bus interface
// that is libusb on a real rig and a simulated bus (sim_hw/sim_usb_relay.h)
// in tests.
//
// Config fields (devices.lights[i]):
//   serial:  the panel's asset tag (a relay channel has no serial of its own)
//   board:   the board's id (5 characters, read from the board; `hairrig
//            devices --discover` prints it), so the board is found whichever
//            USB socket it is in; several lights can share a board
//   channel: 1..N, the relay the panel is wired to
//   bus:     usb (default) | sim: a simulated board powering the scene light
//            `light` (default: the device's name), on a rig with a sim section
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

struct UsbRelayLightOptions {
  std::string board_id;
  int channel = 1;
  std::shared_ptr<UsbRelayBus> bus;  // null: libusb
  // `bus: sim` (a simulated board on the simulated rig; the rig's hook sets
  // `bus`) and `light:` the scene light its channel powers (default: the name).
  bool simulated = false;
  std::string sim_light;
};
Result<UsbRelayLightOptions> ParseUsbRelayLightOptions(const ConfigNode& device);
std::unique_ptr<Light> MakeUsbRelayLight(const DeviceInfo& info, UsbRelayLightOptions options);

using UsbRelayOptionsHook = std::function<Status(const DeviceConfig&, UsbRelayLightOptions*)>;
void RegisterUsbRelayBackend(DeviceRegistry* registry, UsbRelayOptionsHook hook = nullptr);

}  // namespace hairrig
