// A console killed (SIGKILL) in the middle of a capture leaves a capture that
// `hairrig capture --resume` completes, every frame verified: the console
// writes through the same crash-safe dataset as the command line.
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "tests/support/capture_test_util.h"
#include "tests/support/command_run.h"

namespace hairrig {
namespace {

using namespace std::chrono_literals;

// A TCP port nobody listens on right now.
int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), size);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size);
  ::close(fd);
  return ntohs(address.sin_port);
}

pid_t StartConsole(const std::string& captures, int port) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    const std::string listen = "127.0.0.1:" + std::to_string(port);
    ::execl(HAIRRIG_BIN, HAIRRIG_BIN, "serve", "--config", "tests/data/batch_rig.yaml", "--listen",
            listen.c_str(), "--captures", captures.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

TEST(ConsoleKillResume, ACaptureInterruptedWithTheConsoleResumesToCompletion) {
  const std::string captures = testing::FreshDir("console_kill_resume");
  const int port = FreePort();
  const pid_t console = StartConsole(captures, port);
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(60, 0);
  bool up = false;
  for (int i = 0; i < 600 && !up; ++i) {
    auto res = client.Get("/api/state");
    up = res && res->status == 200;
    if (!up) std::this_thread::sleep_for(100ms);
  }
  ASSERT_TRUE(up) << "hairrig serve did not answer within 60 s";
  auto claim = client.Post("/api/control", R"({"client": "test"})", "application/json");
  ASSERT_TRUE(claim && claim->status == 200);
  const std::string lease = nlohmann::json::parse(claim->body)["lease"];
  auto started = client.Post("/api/captures", {{"X-Hairrig-Lease", lease}},
                             R"({"subject": "killed", "calibrate": false})", "application/json");
  ASSERT_TRUE(started && started->status == 202) << (started ? started->body : "no answer");
  const std::string id = nlohmann::json::parse(started->body)["id"];

  int stored = 0;
  for (int i = 0; i < 3000 && stored < 3; ++i) {
    auto state = client.Get("/api/state");
    if (state && state->status == 200) {
      const nlohmann::json s = nlohmann::json::parse(state->body);
      stored = s["capture"].is_object() ? s["capture"]["views_done"].get<int>() : 0;
    }
    if (stored < 3) std::this_thread::sleep_for(20ms);
  }
  ::kill(console, SIGKILL);
  int status = 0;
  ::waitpid(console, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));

  const std::string dir = captures + "/" + id;
  const size_t before = testing::VerifiedFramesOnDisk(dir).size();
  EXPECT_GE(before, 3u);
  EXPECT_LT(before, 16u) << "the kill came after the capture had finished";
  const hairrig_test::CommandRun resumed =
      hairrig_test::Hairrig("capture --resume --out " + dir + " --json");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("\"status\":\"complete\""), std::string::npos) << resumed.output;
  EXPECT_EQ(testing::VerifiedFramesOnDisk(dir).size(), 16u);
}

}  // namespace
}  // namespace hairrig
