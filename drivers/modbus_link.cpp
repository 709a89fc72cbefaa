#include "drivers/modbus_link.h"

#include <modbus/modbus.h>
#include <netdb.h>
#include <sys/socket.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

namespace hairrig {

namespace {

enum class Failure { kTimeout, kMalformed, kConnection, kRetryableException, kException };

Failure Classify(int error) {
  if (error == ETIMEDOUT) return Failure::kTimeout;
  if (error == EMBXACK || error == EMBXSBUSY) return Failure::kRetryableException;
  if (error > MODBUS_ENOBASE && error <= EMBXGTAR) return Failure::kException;
  if (error >= EMBBADCRC && error <= EMBBADSLAVE) return Failure::kMalformed;
  return Failure::kConnection;
}

const char* ExceptionName(int code) {
  switch (code) {
    case MODBUS_EXCEPTION_ILLEGAL_FUNCTION:
      return "illegal function";
    case MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS:
      return "illegal data address";
    case MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE:
      return "illegal data value";
    case MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE:
      return "server device failure";
    case MODBUS_EXCEPTION_ACKNOWLEDGE:
      return "acknowledge (still working)";
    case MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY:
      return "server device busy";
    default:
      return "exception";
  }
}

// What to check, by failure.
const char* Advice(Failure failure, ModbusEndpoint::Transport transport) {
  const bool tcp = transport == ModbusEndpoint::Transport::kTcp;
  switch (failure) {
    case Failure::kTimeout:
      return tcp ? "check that the controller is powered, and its address, port and unit id"
                 : "check power, the RS-485 wiring (A/B), the baud rate and parity, and the slave "
                   "id";
    case Failure::kMalformed:
      return tcp ? "check that the address is the controller's and not another device's"
                 : "check the baud rate, parity, termination resistors and cable length";
    case Failure::kConnection:
      return tcp ? "check the network cable and that no other program holds the controller's only "
                   "connection"
                 : "check that the USB-serial adapter is plugged in";
    default:
      return "see the controller's manual for this exception";
  }
}

// Why a connection to `e` failed, with what to check. `error` is errno after
// modbus_connect, which leaves it unset when its connect() times out.
std::string ConnectFailure(int error, const ModbusEndpoint& e) {
  if (e.transport == ModbusEndpoint::Transport::kRtu) {
    return std::string(error != 0 ? std::strerror(error) : "cannot open the port") + "; " +
           Advice(Failure::kConnection, e.transport);
  }
  if (error == 0 || error == EINPROGRESS || error == ETIMEDOUT) {
    return "no answer within " + std::to_string(e.timeout_ms) +
           " ms; check that the controller is powered and on this network, and its address";
  }
  if (error == ECONNREFUSED) {
    return "connection refused; check the port (Modbus TCP: 502) and that the controller's Modbus "
           "TCP server is on";
  }
  return std::string(std::strerror(error)) + "; " + Advice(Failure::kConnection, e.transport);
}

// True when `host` names an address (libmodbus reports a name that does not
// resolve as a refused connection).
bool Resolves(const std::string& host) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0) return false;
  freeaddrinfo(found);
  return true;
}

// A TCP peer that never gave a Modbus reply on its connection.
Status NotAModbusServer(const ModbusEndpoint& e, Failure failure, int error) {
  return Unavailable(
      "cannot connect to Modbus " + e.Describe() + ": the peer there " +
      (failure == Failure::kMalformed ? "answers, but not in Modbus TCP ("
                                      : "closes the connection before any Modbus reply (") +
      modbus_strerror(error) + "); check that " + e.host + ":" + std::to_string(e.port) +
      " is the controller's address and Modbus TCP port, not another device's");
}

}  // namespace

struct ModbusLink::Context {
  modbus_t* ctx = nullptr;
  bool connected = false;
  ~Context() {
    if (ctx == nullptr) return;
    if (connected) modbus_close(ctx);
    modbus_free(ctx);
  }
};

std::string ModbusEndpoint::Describe() const {
  if (transport == Transport::kTcp) {
    return "tcp " + host + ":" + std::to_string(port) + " unit " + std::to_string(slave_id);
  }
  return "rtu " + device + " " + std::to_string(baud) + " " + std::to_string(data_bits) + parity +
         std::to_string(stop_bits) + " unit " + std::to_string(slave_id);
}

Status ModbusEndpoint::Check() const {
  const auto in = [](int value, int lo, int hi) { return value >= lo && value <= hi; };
  const auto range = [](const char* field, int lo, int hi, int value) {
    return InvalidArgument(std::string(field) + " must lie in " + std::to_string(lo) + ".." +
                           std::to_string(hi) + ", got " + std::to_string(value));
  };
  if (transport == Transport::kTcp) {
    if (host.empty()) return InvalidArgument("host: a TCP controller needs its address");
    if (!in(port, 0, 65535)) return range("port", 0, 65535, port);
  } else {
    if (device.empty()) return InvalidArgument("device: an RTU controller needs its serial device");
    if (!in(baud, 300, 4000000)) return range("baud", 300, 4000000, baud);
    if (parity != 'N' && parity != 'E' && parity != 'O')
      return InvalidArgument("parity must be none, even or odd");
    if (!in(data_bits, 5, 8)) return range("data_bits", 5, 8, data_bits);
    if (!in(stop_bits, 1, 2)) return range("stop_bits", 1, 2, stop_bits);
  }
  if (!in(slave_id, 1, 247)) return range("slave_id", 1, 247, slave_id);
  if (!in(timeout_ms, 1, 60000)) return range("timeout_ms", 1, 60000, timeout_ms);
  if (!in(retries, 0, 20)) return range("retries", 0, 20, retries);
  return Status::Ok();
}

Result<ModbusEndpoint> ParseModbusEndpoint(const ConfigNode& node) {
  ModbusEndpoint e;
  e.transport = node.Choice("transport", {"tcp", "rtu"}, "tcp") == "rtu"
                    ? ModbusEndpoint::Transport::kRtu
                    : ModbusEndpoint::Transport::kTcp;
  if (e.transport == ModbusEndpoint::Transport::kTcp) {
    e.host = node.String("host");
    e.port = node.Integer("port", 502, {.min = 0, .max = 65535});
  } else {
    e.device = node.String("device");
    e.baud = node.Integer("baud", e.baud, {.min = 300, .max = 4000000});
    const std::string parity = node.Choice("parity", {"none", "even", "odd"}, "none");
    e.parity = parity == "even" ? 'E' : parity == "odd" ? 'O' : 'N';
    e.data_bits = node.Integer("data_bits", e.data_bits, {.min = 5, .max = 8});
    e.stop_bits = node.Integer("stop_bits", e.stop_bits, {.min = 1, .max = 2});
  }
  e.slave_id = node.Integer("slave_id", e.slave_id, {.min = 1, .max = 247});
  e.timeout_ms = node.Integer("timeout_ms", e.timeout_ms, {.min = 1, .max = 60000});
  e.retries = node.Integer("retries", e.retries, {.min = 0, .max = 20});
  if (!node.ok()) return node.status();
  return e;
}

ModbusLink::ModbusLink(ModbusEndpoint endpoint) : endpoint_(std::move(endpoint)) {}
ModbusLink::~ModbusLink() = default;

Status ModbusLink::Connect() {
  std::lock_guard<std::mutex> lock(mutex_);
  peer_spoke_modbus_ = false;
  return ConnectLocked();
}

void ModbusLink::Disconnect() {
  std::lock_guard<std::mutex> lock(mutex_);
  DisconnectLocked();
}

void ModbusLink::DisconnectLocked() { context_.reset(); }

Status ModbusLink::ConnectLocked() {
  DisconnectLocked();
  auto c = std::make_unique<Context>();
  const bool tcp = endpoint_.transport == ModbusEndpoint::Transport::kTcp;
  c->ctx = tcp ? modbus_new_tcp_pi(endpoint_.host.c_str(), std::to_string(endpoint_.port).c_str())
               : modbus_new_rtu(endpoint_.device.c_str(), endpoint_.baud, endpoint_.parity,
                                endpoint_.data_bits, endpoint_.stop_bits);
  if (c->ctx == nullptr) {
    return InvalidArgument("cannot set up Modbus " + endpoint_.Describe() + ": " +
                           modbus_strerror(errno));
  }
  modbus_set_slave(c->ctx, endpoint_.slave_id);
  const int ms = endpoint_.timeout_ms;
  modbus_set_response_timeout(c->ctx, static_cast<uint32_t>(ms / 1000),
                              static_cast<uint32_t>(ms % 1000) * 1000);
  if (tcp && !Resolves(endpoint_.host)) {
    return Unavailable("cannot connect to Modbus " + endpoint_.Describe() + ": the host name '" +
                       endpoint_.host +
                       "' does not resolve; check it, or give the controller's IP address");
  }
  errno = 0;
  if (modbus_connect(c->ctx) == -1) {
    return Unavailable("cannot connect to Modbus " + endpoint_.Describe() + ": " +
                       ConnectFailure(errno, endpoint_));
  }
  c->connected = true;
  context_ = std::move(c);
  return Status::Ok();
}

template <typename Request>
Status ModbusLink::Transact(const std::string& what, Request request) {
  Status last;
  for (int attempt = 0; attempt <= endpoint_.retries; ++attempt) {
    if (attempt > 0) ++stats_.retries;
    if (!context_) {
      if (attempt > 0) ++stats_.reconnects;
      last = ConnectLocked();
      if (!last.ok()) continue;
    }
    ++stats_.requests;
    if (request(context_->ctx) != -1) {
      peer_spoke_modbus_ = true;
      return Status::Ok();
    }
    const int error = errno;
    const Failure failure = Classify(error);
    const std::string reason = what + " on Modbus " + endpoint_.Describe();
    const bool tcp = endpoint_.transport == ModbusEndpoint::Transport::kTcp;
    if (tcp && !peer_spoke_modbus_ &&
        (failure == Failure::kMalformed || failure == Failure::kConnection)) {
      // The peer has never answered in Modbus: it is not a Modbus TCP server.
      last = NotAModbusServer(endpoint_, failure, error);
      DisconnectLocked();
      continue;
    }
    switch (failure) {
      case Failure::kException:
      case Failure::kRetryableException: {
        peer_spoke_modbus_ = true;
        const int code = error - MODBUS_ENOBASE;
        last = DeviceFault(reason + ": the controller answered Modbus exception " +
                           std::to_string(code) + " (" + ExceptionName(code) + "); " +
                           Advice(failure, endpoint_.transport));
        if (failure == Failure::kException) return last;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        break;
      }
      case Failure::kTimeout:
        last = Timeout(reason + ": no reply within " + std::to_string(endpoint_.timeout_ms) +
                       " ms; " + Advice(failure, endpoint_.transport));
        break;
      case Failure::kMalformed:
        last = CorruptData(reason + ": malformed reply (" + modbus_strerror(error) + "); " +
                           Advice(failure, endpoint_.transport));
        break;
      case Failure::kConnection:
        last = Unavailable(reason + ": connection lost (" + modbus_strerror(error) + "); " +
                           Advice(failure, endpoint_.transport));
        break;
    }
    if (failure == Failure::kConnection || (tcp && failure != Failure::kRetryableException)) {
      DisconnectLocked();
    } else if (failure == Failure::kMalformed || failure == Failure::kTimeout) {
      modbus_flush(context_->ctx);
    }
  }
  const int attempts = endpoint_.retries + 1;
  return Status(last.code(), last.message() + " (" + std::to_string(attempts) +
                                 (attempts == 1 ? " attempt)" : " attempts)"));
}

Result<std::vector<uint16_t>> ModbusLink::Read(int address, int count) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<uint16_t> values(static_cast<size_t>(count));
  HR_RETURN_IF_ERROR(Transact(
      "reading " + std::to_string(count) + " registers at " + std::to_string(address),
      [&](modbus_t* ctx) { return modbus_read_registers(ctx, address, count, values.data()); }));
  return values;
}

Status ModbusLink::Write(int address, const std::vector<uint16_t>& values) {
  std::lock_guard<std::mutex> lock(mutex_);
  return Transact(
      "writing " + std::to_string(values.size()) + " registers at " + std::to_string(address),
      [&](modbus_t* ctx) {
        return modbus_write_registers(ctx, address, static_cast<int>(values.size()), values.data());
      });
}

ModbusLinkStats ModbusLink::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace hairrig
