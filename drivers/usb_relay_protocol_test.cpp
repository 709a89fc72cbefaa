#include "drivers/usb_relay_protocol.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(UsbRelayProtocol, SwitchReportsCarryTheCommandAndChannel) {
  EXPECT_EQ(*EncodeUsbRelaySwitch(1, true), (UsbRelayReport{0xFF, 1, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(*EncodeUsbRelaySwitch(8, false), (UsbRelayReport{0xFD, 8, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(EncodeUsbRelayAll(true), (UsbRelayReport{0xFE, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(EncodeUsbRelayAll(false), (UsbRelayReport{0xFC, 0, 0, 0, 0, 0, 0, 0}));
  for (int bad : {0, 9, -1}) {
    auto r = EncodeUsbRelaySwitch(bad, true);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("outside 1..8"), std::string::npos);
  }
}

TEST(UsbRelayProtocol, StateReportGivesTheBoardIdAndTheChannelsOn) {
  auto s = DecodeUsbRelayState({'Q', 'A', 'A', 'M', 'Z', 0, 0, 0b00000101});
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->board_id, "QAAMZ");
  EXPECT_TRUE(s->IsOn(1));
  EXPECT_FALSE(s->IsOn(2));
  EXPECT_TRUE(s->IsOn(3));
  EXPECT_FALSE(s->IsOn(9));
  auto short_id = DecodeUsbRelayState({'A', 'B', 0, 0, 0, 0, 0, 0x80});
  EXPECT_EQ(short_id->board_id, "AB");
  EXPECT_TRUE(short_id->IsOn(8));
  auto garbage = DecodeUsbRelayState({'A', 0x01, 'B', 'C', 'D', 0, 0, 0});
  EXPECT_EQ(garbage.status().code(), StatusCode::kCorruptData);
}

}  // namespace
}  // namespace hairrig
