// A Modbus client connection (libmodbus) with the retry and reconnect policy
// a rig needs: register reads and writes that either succeed or return a
// Status saying what went wrong and what to check.
//
// Connecting: Unavailable "cannot connect to Modbus tcp HOST:PORT unit N:
// <why>; check <what>" for a name that does not resolve, a refused
// connection, no answer within `timeout_ms`, and (TCP) a peer that has not
// given one Modbus reply since Connect() and answers in something else or
// hangs up (an HTTP server, a proxy): not a Modbus server.
//
// Failure handling, per request:
//   - no reply within `timeout_ms`           -> retried; then Timeout
//   - malformed reply (CRC, length, framing) -> line flushed, retried; then CorruptData
//   - connection lost (reset, refused, EOF)  -> reconnected, retried; then Unavailable
//   - Modbus exception 5 or 6 (ack, busy)    -> retried after a short wait; then DeviceFault
//   - any other Modbus exception             -> DeviceFault at once (retrying cannot help)
// A TCP link is also reconnected before retrying a timeout or a malformed
// reply, so that a late answer cannot be taken for the next request's.
// Thread-safe: one request at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/config.h"

namespace hairrig {

struct ModbusEndpoint {
  enum class Transport { kTcp, kRtu };
  Transport transport = Transport::kTcp;
  std::string host = "127.0.0.1";  // TCP: address or host name
  int port = 502;
  std::string device;  // RTU: serial device (/dev/ttyUSB0, /dev/serial/by-id/...)
  int baud = 19200;
  char parity = 'N';  // 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  int slave_id = 1;      // unit id (1..247)
  int timeout_ms = 500;  // per request
  int retries = 2;       // further attempts after a failed request

  // "tcp 127.0.0.1:502 unit 1", "rtu /dev/ttyUSB0 19200 8N1 unit 3".
  std::string Describe() const;
  // InvalidArgument naming the config field for a value out of the range
  // ParseModbusEndpoint accepts (a host or device missing for its transport).
  Status Check() const;
};

// Reads transport, host, port, device, baud, parity (none|even|odd),
// data_bits, stop_bits, slave_id, timeout_ms and retries from a device's map.
// Errors name the file, line and field.
Result<ModbusEndpoint> ParseModbusEndpoint(const ConfigNode& device);

struct ModbusLinkStats {
  long requests = 0;
  long retries = 0;
  long reconnects = 0;
};

class ModbusLink {
 public:
  explicit ModbusLink(ModbusEndpoint endpoint);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  const ModbusEndpoint& endpoint() const { return endpoint_; }
  // Unavailable (with the system's reason) when the endpoint cannot be reached.
  Status Connect();
  void Disconnect();
  // Holding registers [address, address + count), count 1..125.
  Result<std::vector<uint16_t>> Read(int address, int count);
  // Holding registers from `address` (function 16), 1..123 values.
  Status Write(int address, const std::vector<uint16_t>& values);
  ModbusLinkStats stats() const;

 private:
  struct Context;
  // Runs `request` (which returns libmodbus' rc) under the retry policy.
  template <typename Request>
  Status Transact(const std::string& what, Request request);
  Status ConnectLocked();
  void DisconnectLocked();

  ModbusEndpoint endpoint_;
  mutable std::mutex mutex_;
  std::unique_ptr<Context> context_;
  ModbusLinkStats stats_;
  bool peer_spoke_modbus_ = false;  // a Modbus reply (data or exception) came since Connect()
};

}  // namespace hairrig
