#include "sim_hw/sim_serve.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>

#include <nlohmann/json.hpp>

namespace hairrig {
namespace {

// Serves the Modbus controller over TCP and RTU (no DSLRs, no GigE fake: those
// need the built camlib and the machine's one GVCP port) until the SIGTERM the
// test sends its own thread once they serve.
TEST(SimServe, ServesUntilAStopSignalAndReportsEachSimulator) {
  SimServeOptions options;
  options.scene_file = "etc/scenes/default.yaml";
  options.time_scale = 0.01;
  options.dslr = false;
  options.gige = false;
  std::string endpoints;
  options.on_serving = [&](const std::string& text) {
    endpoints = text;
    pthread_kill(pthread_self(),
                 SIGTERM);  // blocked in this thread: pending until the wait takes it
  };
  const auto summary = ServeSimulatedDevices(options);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_NE(endpoints.find("try: mbpoll -m tcp -p "), std::string::npos) << endpoints;
  EXPECT_NE(endpoints.find("try: mbpoll -m rtu"), std::string::npos) << endpoints;
  EXPECT_EQ(endpoints.find("gphoto2"), std::string::npos) << endpoints;
  EXPECT_EQ(summary->stopped_by, "SIGTERM");
  EXPECT_EQ(summary->modbus.size(), 2u);
  EXPECT_TRUE(summary->dslr.empty());
  EXPECT_FALSE(summary->gige.has_value());
  const nlohmann::json j = summary->ToJson();
  EXPECT_TRUE(j["gige"].is_null());
  EXPECT_EQ(j["modbus"].size(), 2u);
  EXPECT_EQ(summary->BriefReport().rfind("stopped (SIGTERM)\n", 0), 0u) << summary->BriefReport();

  // The thread's mask is as it was: SIGTERM no longer blocked.
  sigset_t mask;
  pthread_sigmask(SIG_SETMASK, nullptr, &mask);
  EXPECT_EQ(sigismember(&mask, SIGTERM), 0);
}

TEST(SimServe, OptionsOutOfRangeAreNamed) {
  SimServeOptions options;
  options.scene_file = "etc/scenes/default.yaml";
  options.slave_id = 0;
  EXPECT_NE(options.Check().message().find("slave_id"), std::string::npos);
  options.slave_id = 1;
  options.modbus_port = 70000;
  EXPECT_NE(options.Check().message().find("modbus_port"), std::string::npos);
  options.modbus_port = 0;
  options.time_scale = 0;
  EXPECT_NE(options.Check().message().find("time_scale"), std::string::npos);
  options.time_scale = 1;
  EXPECT_TRUE(options.Check().ok());
  const auto refused = ServeSimulatedDevices(SimServeOptions{});
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
