// A capture through the `modbus` turntable driver while its simulated
// controller (sim_hw/modbus_turntable_server.h, which the rig serves because
// the turntable's host is `sim`) is flooded: 1,000 TCP connections held open
// from a thread, then replaced 20 at a time every 20 ms until the capture
// ends. The capture completes with every view verified. Its own executable:
// it raises the open-file limit, and skips (77) where it cannot.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/select.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>

#include "rig/capture.h"
#include "sim_rig/sim_rig.h"
#include "tests/support/capture_test_util.h"
#include "tests/support/modbus_tcp_peer.h"
#include "tests/support/open_file_limit.h"

namespace hairrig {
namespace {

using namespace hairrig::testing;
using Ms = std::chrono::milliseconds;

// The rig these tests build is the simulated one (sim_rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

constexpr size_t kHeld = 1000;
constexpr int kChurnBatch = 20;
constexpr Ms kChurnPeriod{20};
constexpr int kStops = 4;  // 8 views
// The flood's descriptors are moved to this number and above, leaving those
// below FD_SETSIZE to the capture (libmodbus' client select()s on its socket;
// on a real rig a flood's descriptors are another host's, not this process').
constexpr int kFloodFdBase = FD_SETSIZE + 64;

// Connections to one address from a thread: kHeld opened as fast as they go,
// then the oldest kChurnBatch replaced every kChurnPeriod until Stop().
class ConnectionFlood {
 public:
  ~ConnectionFlood() { Stop(); }

  void Start(const sockaddr_in& address) {
    thread_ = std::thread([this, address] { Run(address); });
  }
  // True once kHeld connections are open; false after `limit` or a failure (see error()).
  bool WaitHeld(Ms limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (held_ < kHeld && error_ == 0 && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(Ms(5));
    return held_ >= kHeld;
  }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  long opened() const { return opened_; }
  int error() const { return error_; }

 private:
  // A connection started in the background, its descriptor moved to
  // kFloodFdBase or above; -errno on failure.
  static int Connect(const sockaddr_in& address) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) return -errno;
    if (connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0 &&
        errno != EINPROGRESS) {
      const int error = errno;
      close(fd);
      return -error;
    }
    const int high = fcntl(fd, F_DUPFD_CLOEXEC, kFloodFdBase);
    const int error = errno;
    close(fd);
    return high >= 0 ? high : -error;
  }

  void Run(const sockaddr_in& address) {
    std::deque<int> fds;
    while (!stop_ && fds.size() < kHeld) {
      const int fd = Connect(address);
      if (fd < 0) {
        error_ = -fd;
        break;
      }
      fds.push_back(fd);
      ++opened_;
      held_ = fds.size();
    }
    // Churn: the server keeps accepting (and dropping idle connections) through every move.
    while (!stop_ && error_ == 0) {
      for (int i = 0; i < kChurnBatch && !fds.empty(); ++i) {
        close(fds.front());
        fds.pop_front();
        const int fd =
            Connect(address);  // refused once the capture has ended and its server stopped
        if (fd < 0) continue;
        fds.push_back(fd);
        ++opened_;
      }
      std::this_thread::sleep_for(kChurnPeriod);
    }
    for (int fd : fds) close(fd);
  }

  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> held_{0};
  std::atomic<long> opened_{0};
  std::atomic<int> error_{0};
};

TEST(CaptureUnderModbusFlood, CompletesWithEveryViewVerified) {
  if (!hairrig_test::AllowOpenFiles(kFloodFdBase + kHeld + 512))
    GTEST_SKIP() << "cannot open " << kHeld << " more files in this process";
  const std::string dir = FreshDir("capture_modbus_flood");
  CaptureOptions options;
  options.config_path = WriteSmallRig(
      dir,
      {{"devices",
        SmallRigDevices(
            "{name: turntable, backend: modbus, serial: SIM-TT-0001, transport: tcp, host: sim}",
            "{name: upper, backend: sim, serial: SIM-CAM-UPPER, trigger_line: trig0}",
            "{name: lower, backend: sim, serial: SIM-CAM-LOWER, trigger_line: trig0}")},
       {"plan", "plan:\n  stops: " + std::to_string(kStops) + "\n"}});
  options.out_dir = dir + "/capture";
  sockaddr_in server{};
  std::string served_by;
  options.rig_build.on_built = [&](const Rig& rig) {
    const SimRigState* sim = FindSimRigState(rig);
    ASSERT_NE(sim, nullptr);
    ASSERT_EQ(sim->modbus_servers.size(), 1u);
    server = hairrig_test::ServerAddress(*sim->modbus_servers[0]);
    served_by = sim->modbus_servers[0]->Describe();
  };
  // The flood starts when the first move is announced (the turntable is open
  // and homed), and the capture goes on once every held connection is open.
  ConnectionFlood flood;
  std::once_flag started;
  bool held_before_first_move = false;
  options.on_progress = [&](const CaptureProgress&) {
    std::call_once(started, [&] {
      flood.Start(server);
      held_before_first_move = flood.WaitHeld(Ms(20000));
    });
  };
  const auto start = std::chrono::steady_clock::now();
  const auto summary = RunCapture(options);
  const long opened_during_capture = flood.opened();
  flood.Stop();
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %ld connections opened while %d views were captured in %.1f s (%d faults)\n",
              served_by.c_str(), opened_during_capture, summary->views_planned, wall_s,
              summary->faults);
  EXPECT_EQ(flood.error(), 0) << "the flood could not open its connections: "
                              << std::strerror(flood.error());
  EXPECT_TRUE(held_before_first_move) << "the flood did not reach " << kHeld << " held connections";
  EXPECT_GT(opened_during_capture, static_cast<long>(kHeld))
      << "no connection churned during the moves";

  EXPECT_EQ(summary->status, "complete") << summary->message;
  EXPECT_EQ(summary->views_planned, 2 * kStops);
  EXPECT_EQ(summary->views_completed, summary->views_planned) << summary->message;
  EXPECT_EQ(static_cast<int>(VerifiedFramesOnDisk(summary->dir).size()), summary->views_planned);
  const auto journal = ReadJournal(summary->dir);
  EXPECT_GE(CountEvents(journal, "position_reached"), kStops)
      << "every stop reached under the flood";
  EXPECT_EQ(journal.back()["event"], "session_end");
}

}  // namespace
}  // namespace hairrig
