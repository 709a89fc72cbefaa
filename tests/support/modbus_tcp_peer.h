// Test helper: the simulated Modbus TCP controller on loopback and a raw
// peer of it (sockets without libmodbus, whose select() cannot take
// descriptors past FD_SETSIZE). Header-only, for tests/.
#pragma once

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "sim_hw/modbus_turntable_server.h"
#include "tests/support/sim_world.h"

namespace hairrig_test {

inline constexpr char kModbusSerial[] = "SIM-TT-0001";
inline constexpr int kUnit = 1;
// How long a test waits for a reply that must come (a liveness bound a busy
// machine keeps), and for one that must not (each wait costs that much).
inline constexpr std::chrono::milliseconds kReplyWait{20000};
inline constexpr std::chrono::milliseconds kNoReplyWait{300};

using hairrig::ModbusTurntableServer;

inline sockaddr_in ServerAddress(const ModbusTurntableServer& server) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(server.port()));
  inet_pton(AF_INET, server.host().c_str(), &a.sin_addr);
  return a;
}

// A TCP connection to the server, connecting in the background; -1 on failure.
inline int StartConnection(const ModbusTurntableServer& server) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  const sockaddr_in a = ServerAddress(server);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 && errno != EINPROGRESS) {
    close(fd);
    return -1;
  }
  return fd;
}

// A connected socket (blocking connect with a deadline), for raw requests.
inline int ConnectTo(const ModbusTurntableServer& server) {
  const int fd = StartConnection(server);
  pollfd p{fd, POLLOUT, 0};
  if (fd < 0 || poll(&p, 1, static_cast<int>(kReplyWait.count())) != 1) return -1;
  return fd;
}

// Sends `request` and returns what comes back within `wait`: "" for nothing,
// "closed" when the server closed the connection.
inline std::string Exchange(int fd, const std::vector<uint8_t>& request,
                            std::chrono::milliseconds wait) {
  if (send(fd, request.data(), request.size(), MSG_NOSIGNAL) !=
      static_cast<ssize_t>(request.size()))
    return "closed";
  pollfd p{fd, POLLIN, 0};
  if (poll(&p, 1, static_cast<int>(wait.count())) != 1) return "";
  char reply[300];
  const ssize_t n = recv(fd, reply, sizeof reply, 0);
  return n <= 0 ? "closed" : std::string(reply, static_cast<size_t>(n));
}

// Modbus TCP "read holding registers" (03) of one register at `address` from `unit`.
inline std::vector<uint8_t> ReadRequest(uint8_t unit, int address) {
  return {0x12,
          0x34,
          0,
          0,
          0,
          6,
          unit,
          0x03,
          static_cast<uint8_t>(address >> 8),
          static_cast<uint8_t>(address),
          0,
          1};
}

// The simulated controller serving TCP on loopback as unit kUnit.
struct TcpServerBench {
  std::shared_ptr<hairrig::SimWorld> world = MakeSimWorld();
  std::unique_ptr<ModbusTurntableServer> server;
  TcpServerBench() {
    auto started = ModbusTurntableServer::StartTcp(
        world, {hairrig::ModbusRegisterMap{}, kModbusSerial, kUnit});
    EXPECT_TRUE(started.ok()) << started.status().ToString();
    server = std::move(started).value();
  }
};

}  // namespace hairrig_test
