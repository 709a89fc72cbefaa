// A real Modbus server (libmodbus) that simulates a turntable controller
// behind the register map of drivers/modbus_register_map.h, so that the
// `modbus` driver, and outside tools such as mbpoll, talk to it unchanged.
//
// The motion is the world's turntable controller (sim_hw/sim_turntable_controller.h):
// what a client commands shows in the rendered frames. Per request the server
// refreshes status, fault code and position from the controller, answers
// (libmodbus), then executes a command written to the command register and
// clears that register. It answers function 03 (read holding registers), 06
// and 16 (write); writes to the status, fault code, position or serial
// registers get exception 2 (illegal data address), an unknown command code
// exception 3 (illegal data value), any other function exception 1.
//
// Unit ids: the server answers its own `slave_id` only. On RTU a request to
// unit 0 (broadcast) that writes is executed without a reply (Modbus over
// serial line V1.02, 2.2); on TCP, which has no broadcast, unit 0 is ignored
// like any other unit's request.
//
// Transports: TCP on 127.0.0.1 with an ephemeral port, up to 32 clients at
// once, read with poll() and non-blocking sockets (any number of connections
// or descriptors); past 32 a new connection closes the one idle longest,
// preferring one that never sent a request, so a flood of connections can
// neither stop the server nor lock out a client that polls it. A client that
// sends what is not Modbus TCP is disconnected. RTU over a pseudo-terminal
// pair (openpty) whose client end is device_path(). Faults for tests are
// injected per request (InjectFault). Runs on its own thread from Start*()
// until Stop() or destruction.
#pragma once

#include <memory>
#include <string>

#include "drivers/modbus_register_map.h"
#include "sim_hw/sim_devices.h"

namespace hairrig {

enum class ModbusServerFault {
  kNoReply,         // the request is read and dropped: the client times out
  kException,       // answered with a Modbus exception
  kMalformedReply,  // answered with a well-framed reply of the wrong function
  kDisconnect,      // TCP: the connection is closed; RTU: as kNoReply
};

struct ModbusServerOptions {
  ModbusRegisterMap map;
  std::string serial;  // written to the serial registers
  int slave_id = 1;    // 1..247

  // InvalidArgument naming the field: slave_id out of 1..247, a serial
  // longer than the serial registers hold, counts_per_degree out of
  // [0.001, 1e7].
  Status Check() const;
};

class ModbusTurntableServer {
 public:
  // Serves TCP on `host`:`port` (0 picks a free port; see port()).
  static Result<std::unique_ptr<ModbusTurntableServer>> StartTcp(
      std::shared_ptr<SimWorld> world, ModbusServerOptions options,
      const std::string& host = "127.0.0.1", int port = 0);
  // Serves RTU on the master side of a new pseudo-terminal pair.
  static Result<std::unique_ptr<ModbusTurntableServer>> StartRtu(std::shared_ptr<SimWorld> world,
                                                                 ModbusServerOptions options);
  ~ModbusTurntableServer();
  ModbusTurntableServer(const ModbusTurntableServer&) = delete;
  ModbusTurntableServer& operator=(const ModbusTurntableServer&) = delete;

  int port() const;                 // TCP; 0 for RTU
  std::string host() const;         // TCP; empty for RTU
  std::string device_path() const;  // RTU: the pty a client opens; empty for TCP
  // "modbus tcp 127.0.0.1:40123 unit 1" / "modbus rtu /dev/pts/5 unit 1".
  std::string Describe() const;

  // The next `count` requests meet `fault`; `exception_code` for kException
  // (4 server failure by default; 6 busy is one a client retries).
  void InjectFault(ModbusServerFault fault, int count = 1, int exception_code = 4);
  long requests_served() const;  // requests answered normally
  void Stop();

  struct Impl;

 private:
  explicit ModbusTurntableServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
