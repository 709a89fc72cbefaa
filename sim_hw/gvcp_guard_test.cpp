// The GVCP packet filter on a plain UDP socket on loopback: what reaches the
// socket and what the kernel drops. (tests/aravis_camera_test.cpp sends the
// dropped packets to the guarded GigE fake camera itself.)
#include "sim_hw/gvcp_guard.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <vector>

#include "tests/support/gvcp_packets.h"

namespace hairrig {
namespace {

using namespace hairrig_test;

constexpr uint32_t kRegisters = 0x10000;
constexpr GvcpMemoryLimits kLimits{kRegisters + 1000, kRegisters};

class FilteredSocket {
 public:
  FilteredSocket() {
    receiver_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sender_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    address_.sin_family = AF_INET;
    address_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address_;
    EXPECT_EQ(bind(receiver_, reinterpret_cast<sockaddr*>(&address_), sizeof address_), 0);
    EXPECT_EQ(getsockname(receiver_, reinterpret_cast<sockaddr*>(&address_), &size), 0);
    const Status attached = AttachGvcpFilter(receiver_, kLimits);
    EXPECT_TRUE(attached.ok()) << attached.ToString();
  }
  ~FilteredSocket() {
    close(receiver_);
    close(sender_);
  }

  // Whether `packet` reaches the socket: it is sent, then a packet the filter
  // passes; the first to arrive tells.
  bool Passes(const std::vector<uint8_t>& packet) {
    const std::vector<uint8_t> marker = GvcpCommand(kGvcpReadRegister, {kFakeTestRegister});
    Send(packet);
    Send(marker);
    pollfd p{receiver_, POLLIN, 0};
    if (poll(&p, 1, 2000) != 1) return false;
    std::vector<uint8_t> got(2048);
    const ssize_t n = recv(receiver_, got.data(), got.size(), 0);
    got.resize(n > 0 ? static_cast<size_t>(n) : 0);
    if (got == marker) return false;
    recv(receiver_, got.data(), got.size(), MSG_DONTWAIT);  // the marker
    return true;
  }

 private:
  void Send(const std::vector<uint8_t>& packet) {
    sendto(sender_, packet.data(), packet.size(), 0, reinterpret_cast<const sockaddr*>(&address_),
           sizeof address_);
  }
  int receiver_ = -1, sender_ = -1;
  sockaddr_in address_{};
};

TEST(GvcpGuard, PassesCommandsInsideTheFakesMemory) {
  FilteredSocket s;
  EXPECT_TRUE(s.Passes(GvcpCommand(kGvcpDiscovery, {})));  // discovery
  EXPECT_TRUE(s.Passes(
      GvcpCommand(kGvcpReadRegister, {kLimits.readable_end})));  // the file's end: zero-filled
  EXPECT_TRUE(
      s.Passes(GvcpCommand(kGvcpWriteRegister, {kRegisters - 4, 7})));  // last writable register
  EXPECT_TRUE(s.Passes(GvcpCommand(kGvcpReadMemory, {0, 512})));        // a memory read
  EXPECT_TRUE(s.Passes(
      GvcpCommand(kGvcpReadMemory, {kLimits.readable_end - 103, 104})));  // the file's last words
  EXPECT_TRUE(
      s.Passes(GvcpCommand(kGvcpWriteMemory, {kRegisters - 8, 1})));  // a 4-byte memory write
}

TEST(GvcpGuard, DropsWhatWouldCrashAravisFake) {
  FilteredSocket s;
  EXPECT_FALSE(
      s.Passes(GvcpCommand(kGvcpReadMemory, {0xFFFFFFF0, 4})));  // the crash found by the probe
  EXPECT_FALSE(s.Passes(
      GvcpCommand(kGvcpReadMemory, {kLimits.readable_end + 1, 4})));  // past the GenICam file
  EXPECT_FALSE(
      s.Passes(GvcpCommand(kGvcpReadMemory, {0xFFFF0000, 0xFFFF})));     // address + size wraps
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpReadMemory, {0, 0})));          // size 0
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpReadRegister, {0xFFFFFFFE})));  // register read wraps
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpReadRegister, {kLimits.readable_end + 1})));
  EXPECT_FALSE(
      s.Passes(GvcpCommand(kGvcpWriteRegister, {kRegisters - 3, 7})));  // write into the file
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpWriteRegister, {0xFFFFFFFC, 7})));
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpWriteMemory, {0xFFFFFFFC, 9, 9})));  // memory write wraps
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpWriteMemory, {8}, 2)));           // length < 4: size wraps
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpWriteMemory, {0x100, 9}, 400)));  // data missing
  EXPECT_FALSE(s.Passes(GvcpCommand(kGvcpReadMemory, {0})));               // size missing
  EXPECT_FALSE(s.Passes(GvcpCommand(0x0040, {1, 2, 3})));                  // another command
  EXPECT_FALSE(s.Passes({0x42, 0x01, 0x00}));                              // no header
  std::vector<uint8_t> not_a_command = GvcpCommand(kGvcpReadRegister, {kFakeTestRegister});
  not_a_command[0] = 0x00;
  EXPECT_FALSE(s.Passes(not_a_command));
}

}  // namespace
}  // namespace hairrig
