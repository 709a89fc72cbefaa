#include "drivers/usb_relay_discovery.h"

#include <libusb.h>

#include <cctype>

namespace hairrig {
namespace {

std::string PortPath(libusb_device* device) {
  uint8_t ports[8];
  const int n = libusb_get_port_numbers(device, ports, sizeof(ports));
  std::string path = std::to_string(libusb_get_bus_number(device)) + "-";
  for (int i = 0; i < n; ++i) path += (i ? "." : "") + std::to_string(ports[i]);
  return path;
}

}  // namespace

int UsbRelayChannels(const std::string& product) {
  const std::string prefix = "USBRelay";
  if (product.rfind(prefix, 0) != 0 || product.size() == prefix.size()) return 0;
  for (size_t i = prefix.size(); i < product.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(product[i]))) return 0;
  }
  return std::stoi(product.substr(prefix.size()));
}

std::vector<UsbRelayDetected> DetectUsbRelays() {
  std::vector<UsbRelayDetected> found;
  libusb_context* context = nullptr;
  if (libusb_init(&context) != 0) return found;  // no USB stack (a container): nothing to find
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(context, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0) continue;
    if (descriptor.idVendor != kUsbRelayVendorId || descriptor.idProduct != kUsbRelayProductId) continue;
    UsbRelayDetected d;
    d.port_path = PortPath(list[i]);
    libusb_device_handle* handle = nullptr;
    const int r = libusb_open(list[i], &handle);
    if (r != 0) {
      d.error = std::string("cannot open: ") + libusb_error_name(r) +
                " (add a udev rule giving the rig's user access to 16c0:05df)";
    } else {
      unsigned char text[128] = {};
      if (libusb_get_string_descriptor_ascii(handle, descriptor.iProduct, text, sizeof(text)) > 0) {
        d.product = reinterpret_cast<const char*>(text);
        d.channels = UsbRelayChannels(d.product);
      }
      libusb_close(handle);
    }
    // 16c0:05df is V-USB's shared id: only boards naming themselves USBRelayN are relays.
    if (d.error.empty() && d.channels == 0) continue;
    found.push_back(d);
  }
  libusb_free_device_list(list, 1);
  libusb_exit(context);
  return found;
}

}  // namespace hairrig
