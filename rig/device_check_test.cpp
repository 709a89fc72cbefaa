#include "rig/device_check.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rig/capture_test_util.h"
#include "rig/sim_rig.h"

namespace hairrig {
namespace {

// The small rig is the simulated one (rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

// The small simulated rig: seven devices, each opened and healthy.
TEST(DeviceCheck, EveryDeviceOfTheSmallRigIsOpenedAndHealthy) {
  const std::string config =
      hairrig::testing::WriteSmallRig(hairrig::testing::FreshDir("device_check"));
  const auto summary = CheckDevices({.config_path = config});
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->rig_name, "small simulated rig");
  ASSERT_EQ(summary->devices.size(), 7u);
  EXPECT_EQ(summary->healthy, 7);
  for (const DeviceCheck& d : summary->devices) {
    EXPECT_EQ(d.health, "ok") << d.name;
    EXPECT_EQ(d.backend, "sim") << d.name;
  }
  const nlohmann::json j = summary->ToJson();
  EXPECT_EQ(j["total"], 7);
  EXPECT_EQ(j["devices"][0]["name"], summary->devices[0].name);
  const std::string brief = summary->BriefReport();
  EXPECT_NE(brief.find("SIM-CAM-UPPER"), std::string::npos) << brief;
  EXPECT_NE(brief.find("7 of 7 devices healthy"), std::string::npos) << brief;
}

TEST(DeviceCheck, AMissingConfigIsNamed) {
  const auto summary = CheckDevices({.config_path = "/nonexistent/rig.yaml"});
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("/nonexistent/rig.yaml"), std::string::npos)
      << summary.status().ToString();
}

}  // namespace
}  // namespace hairrig
