// The simulated Modbus TCP controller (sim_hw/modbus_turntable_server.h)
// against hostile peers on loopback: a flood of held connections, requests
// for other unit ids, bytes that are not Modbus. Its client (drivers/
// modbus_link.h) must keep reading registers throughout.
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <arpa/inet.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include "drivers/modbus_link.h"
#include "sim_hw/modbus_turntable_server.h"
#include "tests/support/sim_world.h"

namespace hairrig {
namespace {

constexpr char kSerial[] = "SIM-TT-0001";
constexpr int kUnit = 1;
constexpr int kFlood = 1200;  // past FD_SETSIZE (1024), where libmodbus' select() aborted the process

// Raises this process' soft limit on open files to `wanted` (up to the hard limit).
bool AllowOpenFiles(rlim_t wanted) {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0) return false;
  if (limit.rlim_cur >= wanted) return true;
  if (limit.rlim_max != RLIM_INFINITY && limit.rlim_max < wanted) return false;
  limit.rlim_cur = wanted;
  return setrlimit(RLIMIT_NOFILE, &limit) == 0;
}

sockaddr_in Address(const ModbusTurntableServer& server) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(server.port()));
  inet_pton(AF_INET, server.host().c_str(), &a.sin_addr);
  return a;
}

// A TCP connection to the server, connecting in the background; -1 on failure.
int StartConnection(const ModbusTurntableServer& server) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  const sockaddr_in a = Address(server);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 && errno != EINPROGRESS) {
    close(fd);
    return -1;
  }
  return fd;
}

// A connected socket (blocking connect with a deadline), for raw requests.
int Connect(const ModbusTurntableServer& server) {
  const int fd = StartConnection(server);
  pollfd p{fd, POLLOUT, 0};
  if (fd < 0 || poll(&p, 1, 2000) != 1) return -1;
  return fd;
}

// Sends `request` and returns what comes back within `wait`: "" for nothing,
// "closed" when the server closed the connection.
std::string Exchange(int fd, const std::vector<uint8_t>& request, std::chrono::milliseconds wait) {
  if (send(fd, request.data(), request.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(request.size())) return "closed";
  pollfd p{fd, POLLIN, 0};
  if (poll(&p, 1, static_cast<int>(wait.count())) != 1) return "";
  char reply[300];
  const ssize_t n = recv(fd, reply, sizeof reply, 0);
  return n <= 0 ? "closed" : std::string(reply, static_cast<size_t>(n));
}

// Modbus TCP "read holding registers" (03) of one register at `address` from `unit`.
std::vector<uint8_t> ReadRequest(uint8_t unit, int address) {
  return {0x12, 0x34, 0, 0, 0, 6, unit, 0x03, static_cast<uint8_t>(address >> 8), static_cast<uint8_t>(address), 0, 1};
}

struct Bench {
  std::shared_ptr<SimWorld> world = hairrig_test::MakeSimWorld();
  std::unique_ptr<ModbusTurntableServer> server;
  Bench() {
    auto started = ModbusTurntableServer::StartTcp(world, {ModbusRegisterMap{}, kSerial, kUnit});
    EXPECT_TRUE(started.ok()) << started.status().ToString();
    server = std::move(started).value();
  }
};

TEST(ModbusServer, HeldConnectionFloodNeitherStopsTheServerNorLocksOutItsClient) {
  if (!AllowOpenFiles(kFlood + 512)) GTEST_SKIP() << "cannot open " << kFlood << " files in this process";
  Bench b;
  ModbusEndpoint endpoint;
  endpoint.host = b.server->host();
  endpoint.port = b.server->port();
  endpoint.slave_id = kUnit;
  endpoint.timeout_ms = 5000;
  endpoint.retries = 0;  // a reconnect during the flood would get a descriptor past FD_SETSIZE
  ModbusLink link(endpoint);
  ASSERT_TRUE(link.Connect().ok());  // before the flood: libmodbus' client select()s on its descriptor
  const int status_register = ModbusRegisterMap{}.status;
  ASSERT_TRUE(link.Read(status_register, 1).ok());
  std::vector<int> flood;
  while (flood.size() < static_cast<size_t>(kFlood)) {
    for (int i = 0; i < 100; ++i) {
      const int fd = StartConnection(*b.server);
      ASSERT_GE(fd, 0) << "connection " << flood.size() << ": " << std::strerror(errno);
      flood.push_back(fd);
    }
    auto read = link.Read(status_register, 1);
    ASSERT_TRUE(read.ok()) << "with " << flood.size() << " connections open: " << read.status().ToString();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // every connection reaches the server
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(link.Read(status_register, 1).ok()) << "read " << i << " after the flood";
  // A newcomer still gets in (a silent connection makes room), on a descriptor past FD_SETSIZE.
  const int late = Connect(*b.server);
  ASSERT_GE(late, 0);
  EXPECT_GT(late, 1024);
  EXPECT_EQ(Exchange(late, ReadRequest(kUnit, status_register), std::chrono::milliseconds(2000)).size(), 11u);
  close(late);
  for (int fd : flood) close(fd);
  EXPECT_TRUE(link.Read(status_register, 1).ok());
}

TEST(ModbusServer, AnswersItsOwnUnitIdOnly) {
  Bench b;
  const int fd = Connect(*b.server);
  ASSERT_GE(fd, 0);
  const int status_register = ModbusRegisterMap{}.status;
  for (uint8_t other : {uint8_t{0}, uint8_t{7}, uint8_t{255}}) {
    EXPECT_EQ(Exchange(fd, ReadRequest(other, status_register), std::chrono::milliseconds(300)), "")
        << "unit " << int{other};
  }
  EXPECT_EQ(Exchange(fd, ReadRequest(kUnit, status_register), std::chrono::milliseconds(2000)).size(), 11u);
  close(fd);
}

// Modbus over serial line: unit 0 is a broadcast, a write that every server
// executes and none answers; another unit's requests are not this server's.
TEST(ModbusServer, RtuExecutesBroadcastWritesWithoutReplyingAndIgnoresOtherUnits) {
  auto world = hairrig_test::MakeSimWorld();
  auto server = ModbusTurntableServer::StartRtu(world, {ModbusRegisterMap{}, kSerial, kUnit});
  ASSERT_TRUE(server.ok()) << server.status().ToString();
  modbus_t* ctx = modbus_new_rtu((*server)->device_path().c_str(), 115200, 'N', 8, 1);
  ASSERT_NE(ctx, nullptr);
  ASSERT_EQ(modbus_connect(ctx), 0);
  modbus_set_response_timeout(ctx, 0, 300000);
  const int target = ModbusRegisterMap{}.target;
  const auto write_as = [&](int unit, uint16_t value) {
    modbus_set_slave(ctx, unit);
    const int rc = modbus_write_register(ctx, target, value);
    const int error = errno;
    modbus_flush(ctx);
    return rc == -1 ? error : 0;
  };
  const auto read_as = [&](int unit) {
    modbus_set_slave(ctx, unit);
    uint16_t value = 0;
    const int rc = modbus_read_registers(ctx, target, 1, &value);
    modbus_flush(ctx);
    return rc == 1 ? value : -1;
  };
  EXPECT_EQ(write_as(MODBUS_BROADCAST_ADDRESS, 777), ETIMEDOUT);  // no reply
  EXPECT_EQ(read_as(kUnit), 777);                                 // but executed
  EXPECT_EQ(read_as(MODBUS_BROADCAST_ADDRESS), -1);               // a broadcast read has no answer
  EXPECT_EQ(read_as(kUnit), 777);
  EXPECT_EQ(write_as(7, 555), ETIMEDOUT);
  // libmodbus' RTU server takes the frame after another unit's request for
  // that unit's reply (on a bus it would be) and waits out its response
  // timeout (0.5 s); the request after that is served.
  read_as(kUnit);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(read_as(kUnit), 777);  // unit 7's write was not this server's
  modbus_close(ctx);
  modbus_free(ctx);
}

TEST(ModbusServer, DisconnectsAPeerThatDoesNotSpeakModbus) {
  Bench b;
  const int fd = Connect(*b.server);
  ASSERT_GE(fd, 0);
  const std::string http = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
  EXPECT_EQ(Exchange(fd, std::vector<uint8_t>(http.begin(), http.end()), std::chrono::milliseconds(2000)), "closed");
  close(fd);
  // A request whose PDU is shorter than its function needs is ignored, not read past its end.
  const int fd2 = Connect(*b.server);
  ASSERT_GE(fd2, 0);
  const std::vector<uint8_t> short_write = {0, 1, 0, 0, 0, 4, kUnit, 0x10, 0, 20};
  EXPECT_EQ(Exchange(fd2, short_write, std::chrono::milliseconds(300)), "");
  EXPECT_EQ(Exchange(fd2, ReadRequest(kUnit, ModbusRegisterMap{}.status), std::chrono::milliseconds(2000)).size(), 11u);
  close(fd2);
}

}  // namespace
}  // namespace hairrig
