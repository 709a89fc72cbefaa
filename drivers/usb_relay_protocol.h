// The HID protocol of the common USB relay boards (V-USB firmware, USB id
// 16c0:05df, product "USBRelayN", N = 1, 2, 4 or 8 channels). Facts from the
// boards' published behaviour (e.g. the usbrelay project's documentation):
//   - every exchange is an 8-byte HID feature report, report id 0, on
//     interface 0 (SET_REPORT / GET_REPORT control transfers);
//   - SET 0xFF <channel>: channel on; 0xFD <channel>: off (channels from 1);
//     0xFE: all on; 0xFC: all off;
//   - GET: bytes 0-4 the board's id (5 ASCII characters, set at the factory;
//     the serial hairrig identifies a board by), byte 7 a bit mask of the
//     channels that are on (bit 0 = channel 1).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "core/status.h"

namespace hairrig {

using UsbRelayReport = std::array<uint8_t, 8>;

inline constexpr int kUsbRelayMaxChannels = 8;

// The report that switches `channel` (1..8) on or off; InvalidArgument outside 1..8.
Result<UsbRelayReport> EncodeUsbRelaySwitch(int channel, bool on);
UsbRelayReport EncodeUsbRelayAll(bool on);

struct UsbRelayState {
  std::string board_id;  // trailing NULs and spaces dropped
  uint8_t on_mask = 0;
  bool IsOn(int channel) const {
    return channel >= 1 && channel <= 8 && (on_mask >> (channel - 1)) & 1;
  }
};
// CorruptData when the id holds bytes that are not printable ASCII.
Result<UsbRelayState> DecodeUsbRelayState(const UsbRelayReport& report);

}  // namespace hairrig
