// The rig's extension point with an extension of the test's own: its config
// section, its hooks on a real backend, and a rig built without it.
#include "rig/rig_extension.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/file_util.h"
#include "rig/capture.h"
#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// A relay bus that has no board: every List names the wiring the hook gave it.
class WiringBus : public UsbRelayBus {
 public:
  explicit WiringBus(std::string wire) : wire_(std::move(wire)) {}
  Result<std::vector<Board>> List() override { return Unavailable("wiring bus, wire " + wire_); }
  Status SetReport(const std::string&, const UsbRelayReport&) override {
    return Unavailable("no board");
  }
  Result<UsbRelayReport> GetReport(const std::string&) override { return Unavailable("no board"); }

 private:
  std::string wire_;
};

class NoOpObserver : public CaptureObserver {
 public:
  Status OnCaptureBegin(const CapturePlan&, const CaptureFolder&) override { return Status::Ok(); }
  Status OnCaptureEnd(const CaptureSummary&) override { return Status::Ok(); }
};

// Reads the `wiring` section ({volts: N}); gives `usbrelay` lights with
// `bus: wiring` a WiringBus named by their `wire` field.
class WiringExtension : public RigExtension {
 public:
  std::vector<std::string> ConfigSections() const override { return {"wiring"}; }

  Status CheckConfig(const RigConfig& config) const override {
    if (config.root.Has("wiring"))
      (void)config.root.Child("wiring").Integer("volts", {.min = 1, .max = 48});
    return config.root.status();
  }

  Status Attach(RigAssembly& assembly) const override {
    assembly.rig.extension_states.push_back(std::make_shared<RigExtensionState>());
    assembly.rig.capture_observers.push_back(std::make_shared<NoOpObserver>());
    assembly.hooks.usb_relay.push_back([](const DeviceConfig& c, UsbRelayLightOptions* options) {
      if (options->bus_name == "wiring")
        options->bus = std::make_shared<WiringBus>(c.node.String("wire", "none"));
      return Status::Ok();
    });
    assembly.hooks.usb_relay_fields.push_back("wire");
    return Status::Ok();
  }
};

void RegisterWiring() {
  static const auto extension = std::make_shared<WiringExtension>();
  RegisterRigExtension(extension);
}

std::string WriteConfig(const std::string& name, const std::string& text) {
  const std::string path = testing::FreshDir("rig_extension_" + name) + "/rig.yaml";
  EXPECT_TRUE(WriteFileAtomic(path, text).ok());
  return path;
}

const char kLightOnTheWiringBus[] =
    "devices:\n"
    "  lights:\n"
    "    - {name: top, backend: usbrelay, serial: P1, board: AAAAA, channel: 1,\n"
    "       bus: wiring, wire: b}\n"
    "  cameras: [{name: c, backend: gphoto2, serial: C1}]\n";

TEST(RigExtension, ASectionNoExtensionReadsIsRefusedUnlessIgnored) {
  const std::string path =
      WriteConfig("unclaimed", std::string("surplus: {x: 1}\n") + kLightOnTheWiringBus);
  const auto refused = LoadRigConfig(path);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("unknown field 'surplus'"), std::string::npos)
      << refused.status().ToString();
  EXPECT_TRUE(LoadRigConfig(path, "", UnclaimedSections::kIgnore).ok());
}

TEST(RigExtension, ItsSectionIsCheckedWhenTheConfigIsLoaded) {
  RegisterWiring();
  EXPECT_TRUE(LoadRigConfig(WriteConfig("volts_ok", std::string("wiring: {volts: 24}\n") +
                                                        kLightOnTheWiringBus))
                  .ok());
  const auto bad = LoadRigConfig(
      WriteConfig("volts_bad", std::string("wiring: {volts: 240}\n") + kLightOnTheWiringBus));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("wiring.volts"), std::string::npos)
      << bad.status().ToString();
}

TEST(RigExtension, ItsHooksGiveARealBackendItsBusAndFields) {
  RegisterWiring();
  const auto config = LoadRigConfig(WriteConfig("hooks", kLightOnTheWiringBus));
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  const auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok()) << rig.status().ToString();
  EXPECT_EQ((*rig)->extension_states.size(), 1u);
  EXPECT_EQ((*rig)->capture_observers.size(), 1u);
  ASSERT_EQ((*rig)->devices.lights.size(), 1u);
  const Status opened = (*rig)->devices.lights[0]->Open();
  EXPECT_NE(opened.message().find("wiring bus, wire b"), std::string::npos) << opened.ToString();
}

TEST(RigExtension, ARigBuiltWithoutExtensionsRefusesTheirBus) {
  RegisterWiring();
  const char text[] =
      "devices:\n"
      "  lights:\n"
      "    - {name: top, backend: usbrelay, serial: P1, board: AAAAA, channel: 1, bus: wiring}\n"
      "  cameras: [{name: c, backend: gphoto2, serial: C1}]\n";
  const auto config = LoadRigConfig(WriteConfig("detached", text));
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  RigBuildOptions detached;
  detached.attach_extensions = false;
  const auto rig = BuildRig(*config, detached);
  ASSERT_FALSE(rig.ok());
  EXPECT_NE(rig.status().message().find("bus 'wiring' is not a bus of this rig"), std::string::npos)
      << rig.status().ToString();
  // Its fields are unknown to the backend itself.
  const auto with_field = LoadRigConfig(WriteConfig("detached_field", kLightOnTheWiringBus));
  ASSERT_TRUE(with_field.ok()) << with_field.status().ToString();
  const auto refused = BuildRig(*with_field, detached);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("unknown field"), std::string::npos)
      << refused.status().ToString();
}

}  // namespace
}  // namespace hairrig
