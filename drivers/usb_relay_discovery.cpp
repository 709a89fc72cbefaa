#include "drivers/usb_relay_discovery.h"

#include "drivers/usb_relay.h"

namespace hairrig {

std::vector<UsbRelayDetected> DetectUsbRelays(UsbRelayBus& bus) {
  std::vector<UsbRelayDetected> found;
  auto boards = bus.List();
  if (!boards.ok()) return found;  // no USB stack here (a container): nothing to find
  for (const UsbRelayBus::Board& b : *boards) {
    UsbRelayDetected d{b.port_path, b.product, UsbRelayChannels(b.product), "", ""};
    auto report = bus.GetReport(b.port_path);
    auto state =
        report.ok() ? DecodeUsbRelayState(*report) : Result<UsbRelayState>(report.status());
    if (state.ok())
      d.board_id = state->board_id;
    else
      d.error = state.status().message();
    found.push_back(d);
  }
  return found;
}

std::vector<UsbRelayDetected> DetectUsbRelays() {
  auto bus = MakeLibusbRelayBus();
  return DetectUsbRelays(*bus);
}

}  // namespace hairrig
