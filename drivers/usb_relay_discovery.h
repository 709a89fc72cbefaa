// Finds HID USB relay boards for `hairrig devices --discover`, with each
// board's id (the serial a `usbrelay` light names it by).
#pragma once

#include <string>
#include <vector>

namespace hairrig {

class UsbRelayBus;

struct UsbRelayDetected {
  std::string port_path;  // "1-2.3": bus and port chain, stable for one socket
  std::string product;    // "USBRelay2"
  int channels = 0;       // from the product name
  std::string board_id;   // the board's own id; "" when it could not be read
  std::string error;      // why it could not be read (permissions: a udev rule)
};

std::vector<UsbRelayDetected> DetectUsbRelays(UsbRelayBus& bus);
std::vector<UsbRelayDetected> DetectUsbRelays();  // through libusb

}  // namespace hairrig
