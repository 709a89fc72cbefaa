#include "drivers/registry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/modbus_turntable.h"
#include "drivers/usb_relay.h"
#include "drivers/v4l2_camera.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

// A test light that records its level; stands for any backend.
class TestLight : public Light {
 public:
  using Light::Light;
  LightCapabilities capabilities() const override { return {}; }

 protected:
  Status DoOpen() override {
    SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status DoClose() override { return Status::Ok(); }
  Status DoHealthCheck() override { return Status::Ok(); }
  Status DoSetOn(bool on) override {
    on_ = on;
    return Status::Ok();
  }
  Status DoSetLevel(double level) override { return DoSetOn(level > 0.5); }
  Result<bool> DoIsOn() override { return on_; }

 private:
  bool on_ = false;
};

DeviceRegistry MakeRegistry() {
  DeviceRegistry registry;
  registry.AddBackend<Light>(
      DeviceKind::kLight, "test", [](const DeviceConfig& c) -> Result<std::unique_ptr<Light>> {
        return std::unique_ptr<Light>(std::make_unique<TestLight>(c.Info("test light")));
      });
  return registry;
}

TEST(Registry, BuildsDevicesByBackendName) {
  auto root = ConfigNode::LoadString(
      "devices:\n  lights:\n    - {name: top, backend: test, serial: L1}\n    - {name: bottom, "
      "backend: test, serial: L2}\n"
      "  cameras: []\n",
      "rig.yaml");
  ASSERT_TRUE(root.ok());
  auto set = BuildDevices(root->Child("devices"), MakeRegistry());
  ASSERT_TRUE(set.ok()) << set.status().ToString();
  ASSERT_EQ(set->lights.size(), 2u);
  EXPECT_EQ(set->lights[1]->info().serial, "L2");
  EXPECT_EQ(set->lights[0]->state(), DeviceState::kClosed);
  const Status before_open = set->lights[0]->SetOn(true);
  EXPECT_EQ(before_open.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(before_open.message().find("call Open first"), std::string::npos)
      << before_open.message();
  ASSERT_TRUE(set->OpenAll().ok());
  EXPECT_TRUE(set->lights[0]->SetOn(true).ok());
}

TEST(Registry, UnknownBackendNamesTheFieldAndTheKnownBackends) {
  auto root = ConfigNode::LoadString(
      "devices:\n  lights:\n    - {name: top, backend: gpoid, serial: L1}\n  cameras: []\n",
      "rig.yaml");
  auto set = BuildDevices(root->Child("devices"), MakeRegistry());
  ASSERT_FALSE(set.ok());
  const std::string m = set.status().message();
  EXPECT_NE(m.find("rig.yaml:3:"), std::string::npos) << m;
  EXPECT_NE(m.find("devices.lights[0].backend"), std::string::npos) << m;
  EXPECT_NE(m.find("'gpoid'"), std::string::npos) << m;
  EXPECT_NE(m.find("this build has: test"), std::string::npos) << m;
}

TEST(Registry, DuplicateSerialIsRefused) {
  auto root = ConfigNode::LoadString(
      "devices:\n  lights:\n    - {name: a, backend: test, serial: L1}\n    - {name: b, backend: "
      "test, serial: L1}\n"
      "  cameras: []\n",
      "rig.yaml");
  auto set = BuildDevices(root->Child("devices"), MakeRegistry());
  EXPECT_NE(set.status().message().find("used by two devices"), std::string::npos)
      << set.status().ToString();
}

// The backends' options re-check the ranges their parsers accept, naming the
// config field; their defaults pass (a UVC camera's and a relay light's once
// the fields the config requires are set).
TEST(DriverOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(CameraNominal{}.Check().ok());
  EXPECT_TRUE(AravisCameraOptions{}.Check().ok());
  EXPECT_TRUE(Gphoto2CameraOptions{}.Check().ok());
  EXPECT_TRUE(V4l2CameraOptions{}.Check().ok());
  EXPECT_TRUE(ModbusTurntableOptions{}.Check().ok());
  {
    CameraNominal o;
    o.readout_s = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "readout_s"));
    o = CameraNominal{};
    o.time_scale = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "time_scale"));
  }
  {
    AravisCameraOptions o;
    o.buffers = 1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "buffers"));
    o = AravisCameraOptions{};
    o.packet_size = 20000;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "packet_size"));
    o = AravisCameraOptions{};
    o.nominal.download_s = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "download_s"));
  }
  {
    Gphoto2CameraOptions o;
    o.port = "disk:/tmp/dslr";
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "model"));
    o = Gphoto2CameraOptions{};
    o.busy_attempts = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "busy_attempts"));
    o = Gphoto2CameraOptions{};
    o.busy_backoff_s = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "busy_backoff_s"));
  }
  {
    V4l2CameraOptions o;
    o.buffers = 64;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "buffers"));
    o = V4l2CameraOptions{};
    o.nominal.width_px = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "width_px"));
  }
  {
    UsbRelayLightOptions o;
    o.board_id = "AB12C";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.channel = 9;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "channel"));
    o.channel = 1;
    o.board_id = "TOOLONG";
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "board"));
  }
  {
    ModbusTurntableOptions o;
    o.endpoint.slave_id = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "slave_id"));
    o = ModbusTurntableOptions{};
    o.endpoint.transport = ModbusEndpoint::Transport::kRtu;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "device"));
    o.endpoint.device = "/dev/ttyUSB0";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.endpoint.baud = 100;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "baud"));
    o = ModbusTurntableOptions{};
    o.map.max_speed_deg_s = std::nan("");
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "limits.max_speed_deg_s"));
    o = ModbusTurntableOptions{};
    o.poll_ms = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "poll_ms"));
    o = ModbusTurntableOptions{};
    o.time_scale = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "time_scale"));
  }
}

// A backend checks the options its hook hands back before it builds the
// device, naming the config file's line, the device and the field.
TEST(DriverOptions, TheBackendChecksTheOptionsAfterItsHook) {
  auto root = ConfigNode::LoadString(
      "devices:\n  lights:\n    - {name: top, backend: usbrelay, serial: L1, board: AB12C, "
      "channel: 2}\n  cameras: []\n",
      "rig.yaml");
  ASSERT_TRUE(root.ok()) << root.status().ToString();
  DeviceRegistry registry;
  RegisterUsbRelayBackend(&registry, [](const DeviceConfig&, UsbRelayLightOptions* options) {
    options->channel = 0;
    return Status::Ok();
  });
  auto set = BuildDevices(root->Child("devices"), registry);
  ASSERT_FALSE(set.ok());
  const std::string m = set.status().message();
  EXPECT_EQ(set.status().code(), StatusCode::kInvalidArgument) << m;
  EXPECT_NE(m.find("rig.yaml:3:"), std::string::npos) << m;
  EXPECT_NE(m.find("light top"), std::string::npos) << m;
  EXPECT_NE(m.find("channel"), std::string::npos) << m;
}

}  // namespace
}  // namespace hairrig
