// `hairrig devices --discover`: the real devices this machine can reach,
// each with its serial and a config snippet to paste into a rig config.
// Sources: libgphoto2's auto-detection (each camera opened to read its
// serial), Aravis' interfaces, /dev/video*, libgpiod's chips and HID USB
// relay boards. Nothing simulated is listed (a GigE fake camera served by
// `hairrig sim serve` on loopback is found like a real one).
#pragma once

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/gpio_provider.h"
#include "drivers/usb_relay.h"
#include "drivers/usb_relay_discovery.h"
#include "drivers/uvc_discovery.h"

namespace hairrig {

struct DiscoveredDevice {
  std::string section;  // where the snippet goes under `devices:` ("cameras", "lights")
  std::string backend;  // gphoto2, aravis, v4l2, gpiod, usbrelay
  std::string what;     // "Canon EOS 90D at usb:001,004"
  std::string serial;   // "" when the device has none or it could not be read
  std::string snippet;  // one YAML list item
  std::string note;     // a problem to fix, or what is not supported yet; "" when none
};

// Where each kind of device is looked for; tests replace them.
struct DeviceFinders {
  std::function<Result<std::vector<Gphoto2Detected>>()> gphoto2 = DetectGphoto2Cameras;
  std::function<std::vector<AravisDetected>()> aravis = DetectAravisCameras;
  std::function<std::vector<V4l2Detected>()> v4l2 = [] { return DetectV4l2Cameras(); };
  std::function<std::vector<GpioChipInfo>()> gpio = ListGpioChips;
  std::function<std::vector<UsbRelayDetected>()> relays = [] { return DetectUsbRelays(); };
};

struct Discovery {
  std::vector<DiscoveredDevice> devices;
  std::vector<std::string> problems;  // a source that failed as a whole (libgphoto2 not loading)
};

Discovery DiscoverDevices(const DeviceFinders& finders = {});
nlohmann::json DiscoveryToJson(const Discovery& discovery);
// The report `devices --discover` prints; says plainly when nothing was found.
std::string DiscoveryText(const Discovery& discovery);

}  // namespace hairrig
