#include "rig/device_discovery.h"

#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

// A YAML double-quoted scalar.
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

void AddCameras(const DeviceFinders& finders, Discovery* d) {
  auto dslrs = finders.gphoto2();
  if (!dslrs.ok()) d->problems.push_back("libgphoto2: " + dslrs.status().message());
  int n = 0;
  for (const Gphoto2Detected& c : dslrs.ok() ? *dslrs : std::vector<Gphoto2Detected>{}) {
    d->devices.push_back({"cameras", "gphoto2", c.model + " at " + c.port, c.serial,
                          "- {name: dslr" + std::to_string(++n) +
                              ", backend: gphoto2, serial: " + Quoted(c.serial) + "}",
                          c.error});
  }
  n = 0;
  for (const AravisDetected& c : finders.aravis()) {
    d->devices.push_back({"cameras", "aravis",
                          c.vendor + " " + c.model + " (" + c.protocol + ", " + c.address + ")",
                          c.serial,
                          "- {name: camera" + std::to_string(++n) +
                              ", backend: aravis, serial: " + Quoted(c.serial) + "}",
                          ""});
  }
  n = 0;
  for (const V4l2Detected& c : finders.v4l2()) {
    std::string note = c.error;
    if (c.error.empty() && c.serial.empty()) {
      note = "this camera reports no USB serial: the v4l2 backend needs one to tell cameras apart";
    }
    d->devices.push_back(
        {"cameras", "v4l2",
         (c.card.empty() ? c.path : c.card + " at " + c.path + " (" + c.bus_info + ")"), c.serial,
         "- {name: uvc" + std::to_string(++n) + ", backend: v4l2, serial: " + Quoted(c.serial) +
             "}",
         note});
  }
}

void AddLinesAndRelays(const DeviceFinders& finders, Discovery* d) {
  for (const GpioChipInfo& chip : finders.gpio()) {
    d->devices.push_back(
        {"lights", "gpiod", chip.name + " (" + std::to_string(chip.lines) + " lines)", "",
         "- {name: top, backend: gpiod, serial: PANEL-TOP-01, chip: " + Quoted(chip.label) +
             ", line: 0}",
         "a line has no serial: give it the wired function's asset tag; pick the line wired to "
         "the panel (gpioinfo " +
             chip.name +
             " lists them); the same chip serves trigger_lines "
             "and input_lines"});
  }
  int n = 0;
  for (const UsbRelayDetected& r : finders.relays()) {
    const std::string what = (r.product.empty() ? std::string("USB relay board") : r.product) +
                             " at USB port " + r.port_path +
                             (r.channels ? ", " + std::to_string(r.channels) + " channels" : "");
    d->devices.push_back(
        {"lights", "usbrelay", what, r.board_id,
         "- {name: relay" + std::to_string(++n) +
             ", backend: usbrelay, serial: PANEL-TOP-01, board: " + Quoted(r.board_id) +
             ", channel: 1}",
         r.error.empty() ? "serial is the panel's asset tag; pick the channel it is wired to"
                         : r.error});
  }
}

}  // namespace

Discovery DiscoverDevices(const DeviceFinders& finders) {
  Discovery d;
  AddCameras(finders, &d);
  AddLinesAndRelays(finders, &d);
  return d;
}

nlohmann::json DiscoveryToJson(const Discovery& discovery) {
  nlohmann::json out = {{"devices", nlohmann::json::array()}, {"problems", discovery.problems}};
  for (const DiscoveredDevice& dev : discovery.devices) {
    out["devices"].push_back({{"section", dev.section},
                              {"backend", dev.backend},
                              {"what", dev.what},
                              {"serial", dev.serial},
                              {"snippet", dev.snippet},
                              {"note", dev.note}});
  }
  out["found"] = discovery.devices.size();
  return out;
}

std::string DiscoveryText(const Discovery& discovery) {
  std::string out;
  for (const std::string& p : discovery.problems) out += "problem: " + p + "\n";
  if (discovery.devices.empty()) {
    return out +
           "No devices found: libgphoto2 and Aravis see no camera, and there is no /dev/video*, no "
           "GPIO chip and no "
           "USB relay board. Check that the devices are connected, switched on and accessible to "
           "this user. The "
           "simulated rig (etc/sim-rig.yaml, the default) needs none.\n";
  }
  out += "found " + std::to_string(discovery.devices.size()) +
         " device(s); paste a snippet under `devices:` in "
         "the named section and name it by its role\n";
  for (const DiscoveredDevice& dev : discovery.devices) {
    out += "\n" + dev.backend + ": " + dev.what + "\n";
    out += "  serial: " + (dev.serial.empty() ? std::string("(none read)") : dev.serial) + "\n";
    out += "  " + dev.section + ":\n    " + dev.snippet + "\n";
    if (!dev.note.empty()) out += "  note: " + dev.note + "\n";
  }
  return out;
}

}  // namespace hairrig
