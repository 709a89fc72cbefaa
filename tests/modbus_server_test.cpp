// The simulated Modbus controller (sim_hw/modbus_turntable_server.h) against
// hostile peers: requests for other unit ids, bytes that are not Modbus, RTU
// broadcasts. (tests/modbus_flood_test.cpp floods it with connections.)
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <cerrno>
#include <chrono>
#include <thread>

#include "tests/support/modbus_tcp_peer.h"

namespace hairrig {
namespace {

using namespace hairrig_test;

TEST(ModbusServer, AnswersItsOwnUnitIdOnly) {
  TcpServerBench b;
  const int fd = ConnectTo(*b.server);
  ASSERT_GE(fd, 0);
  const int status_register = ModbusRegisterMap{}.status;
  for (uint8_t other : {uint8_t{0}, uint8_t{7}, uint8_t{255}}) {
    EXPECT_EQ(Exchange(fd, ReadRequest(other, status_register), kNoReplyWait), "")
        << "unit " << int{other};
  }
  EXPECT_EQ(Exchange(fd, ReadRequest(kUnit, status_register), kReplyWait).size(), 11u);
  close(fd);
}

// Modbus over serial line: unit 0 is a broadcast, a write that every server
// executes and none answers; another unit's requests are not this server's.
TEST(ModbusServer, RtuExecutesBroadcastWritesWithoutReplyingAndIgnoresOtherUnits) {
  auto world = hairrig_test::MakeSimWorld();
  auto server = ModbusTurntableServer::StartRtu(world, {ModbusRegisterMap{}, kModbusSerial, kUnit});
  ASSERT_TRUE(server.ok()) << server.status().ToString();
  modbus_t* ctx = modbus_new_rtu((*server)->device_path().c_str(), 115200, 'N', 8, 1);
  ASSERT_NE(ctx, nullptr);
  ASSERT_EQ(modbus_connect(ctx), 0);
  const int target = ModbusRegisterMap{}.target;
  // Each request waits for its reply `limit`: kReplyWait for one that must
  // come, kNoReplyWait for one that must not.
  const auto wait = [&](std::chrono::milliseconds limit) {
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(limit).count();
    modbus_set_response_timeout(ctx, static_cast<uint32_t>(us / 1000000),
                                static_cast<uint32_t>(us % 1000000));
  };
  const auto write_as = [&](int unit, uint16_t value, std::chrono::milliseconds limit) {
    modbus_set_slave(ctx, unit);
    wait(limit);
    const int rc = modbus_write_register(ctx, target, value);
    const int error = errno;
    modbus_flush(ctx);
    return rc == -1 ? error : 0;
  };
  const auto read_as = [&](int unit, std::chrono::milliseconds limit) {
    modbus_set_slave(ctx, unit);
    wait(limit);
    uint16_t value = 0;
    const int rc = modbus_read_registers(ctx, target, 1, &value);
    modbus_flush(ctx);
    return rc == 1 ? value : -1;
  };
  EXPECT_EQ(write_as(MODBUS_BROADCAST_ADDRESS, 777, kNoReplyWait), ETIMEDOUT);  // no reply
  EXPECT_EQ(read_as(kUnit, kReplyWait), 777);                                   // but executed
  // A broadcast read has no answer.
  EXPECT_EQ(read_as(MODBUS_BROADCAST_ADDRESS, kNoReplyWait), -1);
  EXPECT_EQ(read_as(kUnit, kReplyWait), 777);
  EXPECT_EQ(write_as(7, 555, kNoReplyWait), ETIMEDOUT);
  // libmodbus' RTU server takes the frame after another unit's request for
  // that unit's reply (on a bus it would be) and waits out its response
  // timeout (0.5 s); the request after that is served.
  read_as(kUnit, kNoReplyWait);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(read_as(kUnit, kReplyWait), 777);  // unit 7's write was not this server's
  modbus_close(ctx);
  modbus_free(ctx);
}

TEST(ModbusServer, DisconnectsAPeerThatDoesNotSpeakModbus) {
  TcpServerBench b;
  const int fd = ConnectTo(*b.server);
  ASSERT_GE(fd, 0);
  const std::string http = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
  EXPECT_EQ(Exchange(fd, std::vector<uint8_t>(http.begin(), http.end()), kReplyWait), "closed");
  close(fd);
  // A request whose PDU is shorter than its function needs is ignored, not read past its end.
  const int fd2 = ConnectTo(*b.server);
  ASSERT_GE(fd2, 0);
  const std::vector<uint8_t> short_write = {0, 1, 0, 0, 0, 4, kUnit, 0x10, 0, 20};
  EXPECT_EQ(Exchange(fd2, short_write, kNoReplyWait), "");
  EXPECT_EQ(Exchange(fd2, ReadRequest(kUnit, ModbusRegisterMap{}.status), kReplyWait).size(), 11u);
  close(fd2);
}

}  // namespace
}  // namespace hairrig
