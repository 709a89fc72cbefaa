// Finds HID USB relay boards (the common V-USB boards, USB id 16c0:05df,
// product "USBRelayN") for `hairrig devices --discover`; the usbrelay
// backend itself is not built yet.
#pragma once

#include <string>
#include <vector>

namespace hairrig {

struct UsbRelayDetected {
  std::string port_path;  // "1-2.3": bus and port chain, stable for one socket
  std::string product;    // "USBRelay2"
  int channels = 0;       // from the product name; 0 when it does not say
  std::string error;      // why its strings could not be read (permissions: a udev rule)
};

inline constexpr int kUsbRelayVendorId = 0x16c0;
inline constexpr int kUsbRelayProductId = 0x05df;

// The channel count a product string names ("USBRelay2" -> 2), or 0.
int UsbRelayChannels(const std::string& product);

std::vector<UsbRelayDetected> DetectUsbRelays();

}  // namespace hairrig
