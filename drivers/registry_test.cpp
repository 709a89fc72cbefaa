#include "drivers/registry.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

// A test light that records its level; stands for any backend.
class TestLight : public Light {
 public:
  using Light::Light;
  LightCapabilities capabilities() const override { return {}; }
  Status Open() override {
    SetState(DeviceState::kReady);
    return Status::Ok();
  }
  Status Close() override {
    SetState(DeviceState::kClosed);
    return Status::Ok();
  }
  Status HealthCheck() override { return RequireState({DeviceState::kReady}, "HealthCheck"); }
  Status SetOn(bool on) override {
    HR_RETURN_IF_ERROR(RequireState({DeviceState::kReady}, "SetOn"));
    on_ = on;
    return Status::Ok();
  }
  Status SetLevel(double level) override { return SetOn(level > 0.5); }
  Result<bool> IsOn() override { return on_; }

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

}  // namespace
}  // namespace hairrig
