#include "rig/device_check.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sim_rig/sim_rig.h"
#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

// The small rig is the simulated one (sim_rig/sim_rig.h).
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

// A config the capture would refuse is refused here too, naming the field.
TEST(DeviceCheck, UnknownKeysInTheCapturesSectionsAreNamed) {
  const std::map<std::string, std::pair<std::string, std::string>> cases = {
      {"retries", {"retries: {camera: {attempts: 2}, frame_timout_s: 3}\n", "frame_timout_s"}},
      {"storage", {"storage: {min_free_mbb: 10}\n", "min_free_mbb"}},
      {"plan", {"plan: {stops: 2, expsure_s: 0.01}\n", "expsure_s"}},
      {"calibration",
       {"calibration: {box: calib-box.yaml, box_height_mm: 600, box_yw_deg: 3}\n", "box_yw_deg"}}};
  for (const auto& [section, text_and_key] : cases) {
    const std::string dir = hairrig::testing::FreshDir("device_check_" + section);
    const auto summary = CheckDevices(
        {.config_path = hairrig::testing::WriteSmallRig(dir, {{section, text_and_key.first}})});
    ASSERT_FALSE(summary.ok()) << section;
    EXPECT_NE(summary.status().message().find(text_and_key.second), std::string::npos)
        << section << ": " << summary.status().ToString();
  }
}

TEST(DeviceCheck, AMissingConfigIsNamed) {
  const auto summary = CheckDevices({.config_path = "/nonexistent/rig.yaml"});
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("/nonexistent/rig.yaml"), std::string::npos)
      << summary.status().ToString();
}

}  // namespace
}  // namespace hairrig
