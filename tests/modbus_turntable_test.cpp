// The `modbus` turntable driver against the simulated controller, a real
// libmodbus server, over TCP on loopback and RTU over a pseudo-terminal pair;
// and the server against an independent client, mbpoll.
#include "drivers/modbus_turntable.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <thread>

#include "drivers/modbus_link.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/scene.h"
#include "tests/support/sim_world.h"

namespace hairrig {
namespace {

using std::chrono::milliseconds;
constexpr milliseconds kMoveWait{20000};  // a liveness bound, not a speed check
// How long the driver waits for each reply: a bound a busy machine keeps
// (a reply the server withholds costs that much per attempt).
constexpr int kReplyTimeoutMs = 1000;
const MotionProfile kProfile{60.0, 240.0};
// 100 degrees take a second of wall time at the tests' time scale (0.01): what
// a test does while the table moves lands inside the move on a busy machine.
const MotionProfile kSlowProfile{1.0, 240.0};
constexpr char kSerial[] = "SIM-TT-0001";

std::shared_ptr<SimWorld> MakeWorld(std::vector<SimFault> faults = {}) {
  return hairrig_test::MakeSimWorld(std::move(faults));
}

enum class Transport { kTcp, kRtu };

struct Bench {
  std::shared_ptr<SimWorld> world;
  std::unique_ptr<ModbusTurntableServer> server;
  std::unique_ptr<Turntable> table;
};

ModbusTurntableOptions ClientOptions(const ModbusTurntableServer& server, Transport transport,
                                     const ModbusRegisterMap& map) {
  ModbusTurntableOptions o;
  o.map = map;
  o.poll_ms = 2;
  o.endpoint.timeout_ms = kReplyTimeoutMs;
  o.endpoint.retries = 2;
  if (transport == Transport::kTcp) {
    o.endpoint.host = server.host();
    o.endpoint.port = server.port();
  } else {
    o.endpoint.transport = ModbusEndpoint::Transport::kRtu;
    o.endpoint.device = server.device_path();
    o.endpoint.baud = 115200;
  }
  return o;
}

Bench StartBench(Transport transport, const ModbusRegisterMap& map = {},
                 std::vector<SimFault> faults = {}, const std::string& unit_serial = kSerial) {
  Bench b;
  b.world = MakeWorld(std::move(faults));
  ModbusServerOptions server_options{map, unit_serial, 1};
  auto server = transport == Transport::kTcp
                    ? ModbusTurntableServer::StartTcp(b.world, server_options)
                    : ModbusTurntableServer::StartRtu(b.world, server_options);
  EXPECT_TRUE(server.ok()) << server.status().ToString();
  b.server = std::move(server).value();
  const DeviceInfo info{DeviceKind::kTurntable, "turntable", "modbus", kSerial, "test"};
  b.table = MakeModbusTurntable(info, ClientOptions(*b.server, transport, map));
  return b;
}

class ModbusTurntableTest : public ::testing::TestWithParam<Transport> {};

TEST_P(ModbusTurntableTest, HomesAndMovesThePlatformTheRendererSees) {
  Bench b = StartBench(GetParam());
  Turntable& tt = *b.table;
  ASSERT_TRUE(tt.Open().ok());
  auto before = tt.ReadStatus();
  ASSERT_TRUE(before.ok()) << before.status().ToString();
  EXPECT_FALSE(before->homed);
  ASSERT_TRUE(tt.Home(kMoveWait).ok());
  ASSERT_TRUE(tt.StartMove(123.456, kSlowProfile).ok());
  EXPECT_EQ(tt.state(), DeviceState::kBusy);
  auto moving = tt.ReadStatus();
  ASSERT_TRUE(moving.ok());
  EXPECT_FALSE(moving->in_position);
  ASSERT_TRUE(tt.WaitInPosition(kMoveWait).ok());
  auto there = tt.ReadStatus();
  ASSERT_TRUE(there.ok());
  EXPECT_TRUE(there->homed);
  EXPECT_TRUE(there->in_position);
  EXPECT_FALSE(there->moving);
  EXPECT_NEAR(there->position_deg, 123.456, 1e-3);
  EXPECT_NEAR(WorldTurntableAngleDeg(*b.world), 123.456, 1e-9);  // the frames are rendered here
  EXPECT_EQ(tt.state(), DeviceState::kReady);
  EXPECT_TRUE(tt.HealthCheck().ok());
  EXPECT_TRUE(tt.Close().ok());
}

TEST_P(ModbusTurntableTest, RecoversFromOneLostOrMalformedReply) {
  Bench b = StartBench(GetParam());
  Turntable& tt = *b.table;
  ASSERT_TRUE(tt.Open().ok());
  for (ModbusServerFault fault : {ModbusServerFault::kNoReply, ModbusServerFault::kMalformedReply,
                                  ModbusServerFault::kDisconnect}) {
    b.server->InjectFault(fault);
    const long retries = ModbusTurntableLinkStats(tt).retries;
    auto status = tt.ReadStatus();
    EXPECT_TRUE(status.ok()) << static_cast<int>(fault) << ": " << status.status().ToString();
    EXPECT_EQ(ModbusTurntableLinkStats(tt).retries, retries + 1) << static_cast<int>(fault);
  }
  b.server->InjectFault(ModbusServerFault::kException, 1, /*busy*/ 6);
  EXPECT_TRUE(tt.MoveTo(10, kProfile, kMoveWait).ok());
  EXPECT_EQ(tt.state(), DeviceState::kReady);
}

TEST_P(ModbusTurntableTest, PersistentFaultsGiveClearErrorsAndReopenRecovers) {
  Bench b = StartBench(GetParam());
  Turntable& tt = *b.table;
  ASSERT_TRUE(tt.Open().ok());

  b.server->InjectFault(ModbusServerFault::kNoReply, 3);
  Status s = tt.HealthCheck();
  EXPECT_EQ(s.code(), StatusCode::kTimeout) << s.ToString();
  EXPECT_NE(s.message().find("no reply within " + std::to_string(kReplyTimeoutMs) + " ms"),
            std::string::npos)
      << s.message();
  EXPECT_NE(s.message().find("3 attempts"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("turntable 'turntable'"), std::string::npos) << s.message();
  EXPECT_EQ(tt.state(), DeviceState::kFaulted);
  ASSERT_TRUE(tt.Open().ok());

  b.server->InjectFault(ModbusServerFault::kMalformedReply, 3);
  s = tt.HealthCheck();
  EXPECT_EQ(s.code(), StatusCode::kCorruptData) << s.ToString();
  EXPECT_NE(s.message().find("malformed reply"), std::string::npos) << s.message();
  ASSERT_TRUE(tt.Open().ok());

  b.server->InjectFault(ModbusServerFault::kException, 1, /*server failure*/ 4);
  const long requests = ModbusTurntableLinkStats(tt).requests;
  s = tt.StartMove(30, kProfile);
  EXPECT_EQ(s.code(), StatusCode::kDeviceFault) << s.ToString();
  EXPECT_NE(s.message().find("exception 4 (server device failure)"), std::string::npos)
      << s.message();
  EXPECT_EQ(ModbusTurntableLinkStats(tt).requests, requests + 1) << "an exception is not retried";
  ASSERT_TRUE(tt.Open().ok());
  EXPECT_TRUE(tt.MoveTo(30, kProfile, kMoveWait).ok());
}

TEST_P(ModbusTurntableTest, ControllerStallIsADeviceFaultClearedOnReopen) {
  Bench b = StartBench(GetParam(), {},
                       {SimFault{.kind = SimFaultKind::kTurntableStall, .device = "", .at = 2}});
  Turntable& tt = *b.table;
  ASSERT_TRUE(tt.Open().ok());
  ASSERT_TRUE(tt.Home(kMoveWait).ok());  // move 1
  Status s = tt.MoveTo(180, kProfile, kMoveWait);
  EXPECT_EQ(s.code(), StatusCode::kDeviceFault) << s.ToString();
  EXPECT_NE(s.message().find("fault code 1"), std::string::npos) << s.message();
  EXPECT_EQ(tt.state(), DeviceState::kFaulted);
  auto stalled = tt.ReadStatus();
  ASSERT_TRUE(stalled.ok());
  EXPECT_TRUE(stalled->fault);
  EXPECT_LT(stalled->position_deg, 179);
  ASSERT_TRUE(tt.Open().ok());  // clears the latched fault
  auto cleared = tt.ReadStatus();
  ASSERT_TRUE(cleared.ok());
  EXPECT_FALSE(cleared->fault);
  EXPECT_TRUE(tt.MoveTo(180, kProfile, kMoveWait).ok());
}

TEST_P(ModbusTurntableTest, StopFromAnotherThreadEndsTheWait) {
  Bench b = StartBench(GetParam());
  Turntable& tt = *b.table;
  ASSERT_TRUE(tt.Open().ok());
  ASSERT_TRUE(tt.StartMove(359, kSlowProfile).ok());
  std::thread stopper([&] {
    std::this_thread::sleep_for(milliseconds(50));
    EXPECT_TRUE(tt.Stop().ok());
  });
  const Status s = tt.WaitInPosition(kMoveWait);
  stopper.join();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  const double stopped_at = WorldTurntableAngleDeg(*b.world);
  std::this_thread::sleep_for(milliseconds(50));
  EXPECT_EQ(WorldTurntableAngleDeg(*b.world), stopped_at);
  EXPECT_LT(stopped_at, 359);
}

INSTANTIATE_TEST_SUITE_P(Transports, ModbusTurntableTest,
                         ::testing::Values(Transport::kTcp, Transport::kRtu),
                         [](const auto& param) {
                           return param.param == Transport::kTcp ? "Tcp" : "Rtu";
                         });

TEST(ModbusTurntable, LowWordFirstMapAndNegativeAngles) {
  ModbusRegisterMap map;
  map.word_order = WordOrder::kLowFirst;
  map.counts_per_degree = 3600;
  map.position = 40;
  map.target = 20;
  Bench b = StartBench(Transport::kTcp, map);
  ASSERT_TRUE(b.table->Open().ok());
  ASSERT_TRUE(b.table->MoveTo(-37.25, kProfile, kMoveWait).ok());
  auto s = b.table->ReadStatus();
  ASSERT_TRUE(s.ok());
  EXPECT_NEAR(s->position_deg, -37.25, 1.0 / 3600);
  EXPECT_NEAR(WorldTurntableAngleDeg(*b.world), -37.25, 1e-9);
}

TEST(ModbusTurntable, RefusesAControllerWithAnotherSerial) {
  Bench b = StartBench(Transport::kTcp, {}, {}, "TT-OTHER-7");
  const Status s = b.table->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("TT-OTHER-7"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(kSerial), std::string::npos) << s.message();
  EXPECT_EQ(b.table->state(), DeviceState::kFaulted);
}

TEST(ModbusTurntable, NoServerIsUnavailableNamingTheEndpoint) {
  Bench b = StartBench(Transport::kTcp);
  const int port = b.server->port();
  b.server.reset();  // nothing listens on the port any more
  const Status s = b.table->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("127.0.0.1:" + std::to_string(port)), std::string::npos)
      << s.message();
}

// A listening TCP socket on 127.0.0.1 with an ephemeral port.
int ListenOnLoopback(int backlog, int* port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof a;
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      listen(fd, backlog) != 0 || getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length) != 0) {
    return -1;
  }
  *port = ntohs(a.sin_port);
  return fd;
}

// A TCP peer that answers whatever it is sent in HTTP, then hangs up (what a
// web server, or a proxy intercepting an unreachable address, does).
class HttpPeer {
 public:
  HttpPeer() : fd_(ListenOnLoopback(8, &port_)), thread_([this] { Serve(); }) {}
  ~HttpPeer() {
    stop_ = true;
    thread_.join();
    close(fd_);
  }
  int port() const { return port_; }

 private:
  void Serve() {
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 20) != 1) continue;
      const int client = accept(fd_, nullptr, nullptr);
      if (client < 0) continue;
      pollfd c{client, POLLIN, 0};
      char request[512];
      if (poll(&c, 1, 1000) == 1 && recv(client, request, sizeof request, 0) > 0) {
        const std::string reply =
            "HTTP/1.1 400 Bad Request\r\nconnection: close\r\ncontent-length: 0\r\n\r\n";
        (void)!send(client, reply.data(), reply.size(), MSG_NOSIGNAL);
      }
      close(client);
    }
  }

  int port_ = 0;
  int fd_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

ModbusEndpoint LoopbackEndpoint(int port, int timeout_ms) {
  ModbusEndpoint e;
  e.host = "127.0.0.1";
  e.port = port;
  e.timeout_ms = timeout_ms;
  e.retries = 1;
  return e;
}

// Such a peer was reported as a Modbus controller sending a "malformed reply".
TEST(ModbusLink, APeerThatDoesNotSpeakModbusIsCannotConnect) {
  HttpPeer peer;
  ModbusLink link(LoopbackEndpoint(peer.port(), kReplyTimeoutMs));
  ASSERT_TRUE(link.Connect().ok());  // TCP connects; the first request shows what answers
  auto read = link.Read(100, 8);
  ASSERT_FALSE(read.ok());
  const std::string m = read.status().message();
  EXPECT_EQ(read.status().code(), StatusCode::kUnavailable) << m;
  const std::string endpoint = "127.0.0.1:" + std::to_string(peer.port());
  EXPECT_NE(m.find("cannot connect to Modbus tcp " + endpoint), std::string::npos) << m;
  EXPECT_NE(m.find("check that " + endpoint + " is the controller's address and Modbus TCP port"),
            std::string::npos)
      << m;
}

// A listener whose accept queue is full drops further connection requests,
// as an unreachable host does: the connection attempt times out.
TEST(ModbusLink, AHostThatDoesNotAnswerIsCannotConnectWithinTheTimeout) {
  int port = 0;
  const int listener = ListenOnLoopback(0, &port);
  ASSERT_GE(listener, 0);
  std::vector<int> fillers;
  for (int i = 0; i < 3; ++i) {
    fillers.push_back(socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    (void)!connect(fillers.back(), reinterpret_cast<sockaddr*>(&a), sizeof a);
  }
  std::this_thread::sleep_for(milliseconds(100));
  ModbusLink link(LoopbackEndpoint(port, 200));
  const Status s = link.Connect();
  for (int fd : fillers) close(fd);
  close(listener);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("cannot connect to Modbus tcp 127.0.0.1:" + std::to_string(port) +
                             " unit 1: no answer within 200 ms; check"),
            std::string::npos)
      << s.message();
}

TEST(ModbusLink, AHostNameThatDoesNotResolveIsNamed) {
  ModbusEndpoint e = LoopbackEndpoint(502, 200);
  e.host = "no-such-controller.invalid";
  const Status s = ModbusLink(e).Connect();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("'no-such-controller.invalid' does not resolve"), std::string::npos)
      << s.message();
}

TEST(ModbusTurntable, ServerRefusesReadOnlyRegistersAndUnknownCommands) {
  Bench b = StartBench(Transport::kTcp);
  ModbusEndpoint e;
  e.port = b.server->port();
  e.retries = 0;
  ModbusLink link(e);
  ASSERT_TRUE(link.Connect().ok());
  Status s = link.Write(ModbusRegisterMap{}.position, {1, 2});
  EXPECT_EQ(s.code(), StatusCode::kDeviceFault);
  EXPECT_NE(s.message().find("exception 2 (illegal data address)"), std::string::npos)
      << s.message();
  s = link.Write(ModbusRegisterMap{}.command, {99});
  EXPECT_NE(s.message().find("exception 3 (illegal data value)"), std::string::npos) << s.message();
  auto serial = link.Read(ModbusRegisterMap{}.serial, ModbusRegisterMap{}.serial_registers);
  ASSERT_TRUE(serial.ok());
  EXPECT_EQ(DecodeAscii(serial->data(), static_cast<int>(serial->size())), kSerial);
}

// --- conformance against an independent client ------------------------------

// Runs mbpoll against `endpoint_args`; its stdout, or nullopt when it failed.
std::optional<std::string> Mbpoll(const std::string& endpoint_args, const std::string& request) {
  const std::string command = "mbpoll " + endpoint_args + " -a 1 -0 -1 -o 2 " + request + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  std::string out;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  const int rc = pclose(pipe);
  if (rc != 0) {
    ADD_FAILURE() << command << " exited " << rc << ":\n" << out;
    return std::nullopt;
  }
  return out;
}

bool HaveMbpoll() { return std::system("command -v mbpoll >/dev/null 2>&1") == 0; }

class MbpollConformance : public ::testing::TestWithParam<Transport> {};

TEST_P(MbpollConformance, ReadsAndWritesTheSimulatedControllersRegisters) {
  if (!HaveMbpoll()) GTEST_FAIL() << "mbpoll is not installed: run scripts/install-deps";
  Bench b = StartBench(GetParam());
  const std::string where = GetParam() == Transport::kTcp
                                ? "-m tcp -p " + std::to_string(b.server->port()) + " 127.0.0.1"
                                : "-m rtu -b 115200 -P none " + b.server->device_path();
  // The serial registers, as mbpoll prints them: [100]: 0x5349 ("SI") ...
  auto serial = Mbpoll(where, "-t 4:hex -r 100 -c 2");
  ASSERT_TRUE(serial);
  EXPECT_NE(serial->find("[100]: \t0x5349"), std::string::npos) << *serial;
  EXPECT_NE(serial->find("[101]: \t0x4D2D"), std::string::npos) << *serial;
  // Target 45 deg, speed 60 deg/s, acceleration 240 deg/s^2 (32-bit, high word first), then
  // move_absolute.
  ASSERT_TRUE(Mbpoll(where, "-t 4:int -B -r 12 45000 60000 240000"));
  ASSERT_TRUE(Mbpoll(where, "-t 4 -r 0 1"));
  std::string position;
  for (int i = 0; i < 200 && position.find("45000") == std::string::npos; ++i) {
    std::this_thread::sleep_for(milliseconds(20));
    position = Mbpoll(where, "-t 4:int -B -r 10").value_or("");
  }
  EXPECT_NE(position.find("[10]: \t45000"), std::string::npos) << position;
  EXPECT_NEAR(WorldTurntableAngleDeg(*b.world), 45.0, 1e-9);
  // Status bits: in position (bit 0) once settled; not homed, not moving, no fault.
  std::string status;
  for (int i = 0; i < 50 && status.find("[1]: \t1\n") == std::string::npos; ++i) {
    std::this_thread::sleep_for(milliseconds(20));
    status = Mbpoll(where, "-t 4 -r 1").value_or("");
  }
  EXPECT_NE(status.find("[1]: \t1\n"), std::string::npos) << status;
}

INSTANTIATE_TEST_SUITE_P(Transports, MbpollConformance,
                         ::testing::Values(Transport::kTcp, Transport::kRtu),
                         [](const auto& param) {
                           return param.param == Transport::kTcp ? "Tcp" : "Rtu";
                         });

}  // namespace
}  // namespace hairrig
