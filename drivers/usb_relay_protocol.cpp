#include "drivers/usb_relay_protocol.h"

namespace hairrig {

Result<UsbRelayReport> EncodeUsbRelaySwitch(int channel, bool on) {
  if (channel < 1 || channel > kUsbRelayMaxChannels) {
    return InvalidArgument("relay channel " + std::to_string(channel) + " is outside 1.." +
                           std::to_string(kUsbRelayMaxChannels));
  }
  return UsbRelayReport{
      static_cast<uint8_t>(on ? 0xFF : 0xFD), static_cast<uint8_t>(channel), 0, 0, 0, 0, 0, 0};
}

UsbRelayReport EncodeUsbRelayAll(bool on) {
  return {static_cast<uint8_t>(on ? 0xFE : 0xFC), 0, 0, 0, 0, 0, 0, 0};
}

Result<UsbRelayState> DecodeUsbRelayState(const UsbRelayReport& report) {
  UsbRelayState state;
  for (int i = 0; i < 5; ++i) {
    const uint8_t c = report[static_cast<size_t>(i)];
    if (c == 0) break;
    if (c < 0x20 || c > 0x7e) {
      return CorruptData("relay board state report: byte " + std::to_string(i) +
                         " of the board id is 0x" + std::to_string(c) + ", not printable ASCII");
    }
    state.board_id += static_cast<char>(c);
  }
  while (!state.board_id.empty() && state.board_id.back() == ' ') state.board_id.pop_back();
  state.on_mask = report[7];
  return state;
}

}  // namespace hairrig
