// `devices --discover`'s report, from stand-in finders (these machines have
// no camera, GPIO chip or relay board), and the real finders' empty answer.
#include "rig/device_discovery.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

DeviceFinders NoneFound() {
  DeviceFinders f;
  f.gphoto2 = [] { return Result<std::vector<Gphoto2Detected>>(std::vector<Gphoto2Detected>{}); };
  f.aravis = [] { return std::vector<AravisDetected>{}; };
  f.v4l2 = [] { return std::vector<V4l2Detected>{}; };
  f.gpio = [] { return std::vector<GpioChipInfo>{}; };
  f.relays = [] { return std::vector<UsbRelayDetected>{}; };
  return f;
}

TEST(DeviceDiscovery, NothingFoundIsSaidPlainly) {
  const Discovery d = DiscoverDevices(NoneFound());
  EXPECT_TRUE(d.devices.empty());
  EXPECT_NE(DiscoveryText(d).find("No devices found"), std::string::npos);
  EXPECT_EQ(DiscoveryToJson(d)["found"], 0);
}

TEST(DeviceDiscovery, EachDeviceComesWithItsSerialAndASnippetToPaste) {
  DeviceFinders f = NoneFound();
  f.gphoto2 = [] {
    return Result<std::vector<Gphoto2Detected>>(
        std::vector<Gphoto2Detected>{{"Canon EOS 90D", "usb:001,004", "0320\"21", ""}});
  };
  f.aravis = [] {
    return std::vector<AravisDetected>{
        {"Basler-22104387", "Basler", "acA2440-20gc", "22104387", "192.168.10.31", "GigEVision"}};
  };
  f.v4l2 = [] {
    return std::vector<V4l2Detected>{{"/dev/video0", "C920", "uvcvideo", "usb-1", "A1B2", ""}};
  };
  f.gpio = [] { return std::vector<GpioChipInfo>{{"gpiochip0", "pinctrl-bcm2711", 58}}; };
  f.relays = [] { return std::vector<UsbRelayDetected>{{"1-2.3", "USBRelay2", 2, "QAAMZ", ""}}; };
  const Discovery d = DiscoverDevices(f);
  ASSERT_EQ(d.devices.size(), 5u);
  EXPECT_EQ(d.devices[0].snippet, "- {name: dslr1, backend: gphoto2, serial: \"0320\\\"21\"}");
  EXPECT_EQ(d.devices[1].snippet, "- {name: camera1, backend: aravis, serial: \"22104387\"}");
  EXPECT_EQ(d.devices[1].what, "Basler acA2440-20gc (GigEVision, 192.168.10.31)");
  EXPECT_EQ(d.devices[2].snippet, "- {name: uvc1, backend: v4l2, serial: \"A1B2\"}");
  EXPECT_NE(d.devices[3].snippet.find("chip: \"pinctrl-bcm2711\""), std::string::npos);
  EXPECT_NE(d.devices[4].what.find("2 channels"), std::string::npos);
  EXPECT_EQ(
      d.devices[4].snippet,
      "- {name: relay1, backend: usbrelay, serial: PANEL-TOP-01, board: \"QAAMZ\", channel: 1}");
  const std::string text = DiscoveryText(d);
  EXPECT_NE(text.find("found 5 device(s)"), std::string::npos) << text;
  EXPECT_NE(text.find("serial: 22104387"), std::string::npos) << text;
  // The snippet is valid YAML that reads back the serial.
  auto node = ConfigNode::LoadString(d.devices[0].snippet.substr(2), "snippet");
  ASSERT_TRUE(node.ok());
  EXPECT_EQ(node->String("serial"), "0320\"21");
}

TEST(DeviceDiscovery, AFailingSourceIsNamedAndTheOthersStillRun) {
  DeviceFinders f = NoneFound();
  f.gphoto2 = [] {
    return Result<std::vector<Gphoto2Detected>>(IoError("cannot load its camera drivers"));
  };
  f.gpio = [] { return std::vector<GpioChipInfo>{{"gpiochip0", "x", 8}}; };
  const Discovery d = DiscoverDevices(f);
  ASSERT_EQ(d.problems.size(), 1u);
  EXPECT_NE(DiscoveryText(d).find("problem: libgphoto2: cannot load"), std::string::npos);
  EXPECT_EQ(d.devices.size(), 1u);
}

TEST(DeviceDiscovery, RelayChannelsComeFromTheProductName) {
  EXPECT_EQ(UsbRelayChannels("USBRelay2"), 2);
  EXPECT_EQ(UsbRelayChannels("USBRelay8"), 8);
  EXPECT_EQ(UsbRelayChannels("USBRelay16"), 0);  // no such board: 8 channels at most
  EXPECT_EQ(UsbRelayChannels("USBasp"), 0);
  EXPECT_EQ(UsbRelayChannels("USBRelay"), 0);
}

}  // namespace
}  // namespace hairrig
