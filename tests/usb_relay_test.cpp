// The `usbrelay` light backend against simulated HID relay boards behind
// its bus interface; discovery over the same bus.
#include "drivers/usb_relay.h"

#include <gtest/gtest.h>

#include "drivers/usb_relay_discovery.h"
#include "sim_hw/sim_usb_relay.h"

namespace hairrig {
namespace {

struct Bench {
  std::shared_ptr<SimUsbRelayBus> bus = std::make_shared<SimUsbRelayBus>();
  Bench() {
    EXPECT_TRUE(bus->AddBoard({"1-2", "AAAAA", 2, {}}).ok());
    EXPECT_TRUE(bus->AddBoard({"1-3.1", "QAAMZ", 4, {}}).ok());
  }
  std::unique_ptr<Light> MakeLight(const std::string& id, int channel) {
    UsbRelayLightOptions o;
    o.board_id = id;
    o.channel = channel;
    o.bus = bus;
    return MakeUsbRelayLight({DeviceKind::kLight, "top", "usbrelay", "PANEL-TOP-01", "test"}, o);
  }
};

TEST(UsbRelay, FindsTheBoardByIdAndSwitchesItsChannel) {
  Bench b;
  auto light = b.MakeLight("QAAMZ", 3);
  ASSERT_TRUE(light->Open().ok());
  ASSERT_TRUE(light->HealthCheck().ok());
  ASSERT_TRUE(light->SetOn(true).ok());
  EXPECT_EQ(b.bus->Mask("1-3.1"), 0b0100);
  EXPECT_EQ(b.bus->Mask("1-2"), 0);  // the other board untouched
  EXPECT_TRUE(*light->IsOn());
  ASSERT_TRUE(light->SetLevel(0.0).ok());
  EXPECT_EQ(b.bus->Mask("1-3.1"), 0);
  EXPECT_EQ(light->SetLevel(0.5).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(light->SetLevel(2.0).code(), StatusCode::kOutOfRange);
}

TEST(UsbRelay, ClosingSwitchesThePanelOff) {
  Bench b;
  auto light = b.MakeLight("AAAAA", 1);
  ASSERT_TRUE(light->Open().ok());
  ASSERT_TRUE(light->SetOn(true).ok());
  EXPECT_EQ(b.bus->Mask("1-2"), 1);
  ASSERT_TRUE(light->Close().ok());
  EXPECT_EQ(b.bus->Mask("1-2"), 0);
}

TEST(UsbRelay, AnUnknownIdOrChannelIsRefused) {
  Bench b;
  auto missing = b.MakeLight("ZZZZZ", 1);
  Status s = missing->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("'QAAMZ' at 1-3.1"), std::string::npos) << s.message();
  auto beyond = b.MakeLight("AAAAA", 3);
  s = beyond->Open();
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange) << s.ToString();
  EXPECT_NE(s.message().find("USBRelay2"), std::string::npos) << s.message();
}

TEST(UsbRelay, AStuckRelayIsADeviceFault) {
  Bench b;
  b.bus->StickChannel("1-2", 2);
  auto light = b.MakeLight("AAAAA", 2);
  ASSERT_TRUE(light->Open().ok());
  const Status s = light->SetOn(true);
  EXPECT_EQ(s.code(), StatusCode::kDeviceFault) << s.ToString();
  EXPECT_NE(s.message().find("did not switch on"), std::string::npos) << s.message();
  EXPECT_EQ(light->state(), DeviceState::kFaulted);
}

TEST(UsbRelay, AnUnpluggedBoardFaultsAndIsFoundAgainOnAnotherPort) {
  Bench b;
  auto light = b.MakeLight("AAAAA", 1);
  ASSERT_TRUE(light->Open().ok());
  b.bus->Unplug("1-2");
  const Status s = light->SetOn(true);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_EQ(light->state(), DeviceState::kFaulted);
  EXPECT_EQ(light->Open().code(), StatusCode::kUnavailable);
  // Plugged back into another socket: found by its id.
  ASSERT_TRUE(b.bus->AddBoard({"2-1", "AAAAA", 2, {}}).ok());
  ASSERT_TRUE(light->Open().ok());
  ASSERT_TRUE(light->SetOn(true).ok());
  EXPECT_EQ(b.bus->Mask("2-1"), 1);
}

TEST(UsbRelay, DiscoveryReadsEachBoardsId) {
  Bench b;
  const auto found = DetectUsbRelays(*b.bus);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].board_id, "AAAAA");
  EXPECT_EQ(found[0].channels, 2);
  EXPECT_EQ(found[1].port_path, "1-3.1");
  EXPECT_EQ(found[1].board_id, "QAAMZ");
  EXPECT_EQ(found[1].channels, 4);
}

TEST(UsbRelay, ConfigNeedsAChannel) {
  auto root = ConfigNode::LoadString("{name: top, backend: usbrelay, serial: P1, board: AAAAA}",
                                     "rig.yaml");
  auto parsed = ParseUsbRelayLightOptions(*root);
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.status().message().find("channel"), std::string::npos)
      << parsed.status().message();
}

}  // namespace
}  // namespace hairrig
