#include "sim_hw/modbus_turntable_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/eventfd.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "sim_hw/sim_turntable_controller.h"

namespace hairrig {

namespace {

constexpr int kReadHolding = 0x03;
constexpr int kWriteSingle = 0x06;
constexpr int kWriteMultiple = 0x10;
// TCP connections served at once; a real controller allows a handful.
constexpr size_t kMaxTcpClients = 32;
constexpr int kListenBacklog = 64;
constexpr int kRtuCrcBytes = 2;

uint16_t Word(const uint8_t* bytes) { return static_cast<uint16_t>((bytes[0] << 8) | bytes[1]); }

// Modbus RTU CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF).
uint16_t Crc16(const uint8_t* data, size_t size) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 1u) ? static_cast<uint16_t>((crc >> 1) ^ 0xA001u) : crc >> 1;
  }
  return crc;
}

struct PendingFault {
  ModbusServerFault fault;
  int exception_code;
};

using Clock = std::chrono::steady_clock;

// A TCP client and the bytes of its request still on the way.
struct TcpClient {
  int fd = -1;
  std::vector<uint8_t> pending;
  bool spoke = false;  // has sent a request
  Clock::time_point last_active;
};

// Bytes of the first Modbus TCP request at the front of `bytes` (MBAP header:
// transaction, protocol 0, length of what follows, unit id): 0 while
// incomplete, -1 when the bytes cannot be Modbus TCP.
int CompleteTcpFrame(const std::vector<uint8_t>& bytes) {
  if (bytes.size() < 6) return 0;
  const int protocol = Word(&bytes[2]);
  const int length = Word(&bytes[4]);
  if (protocol != 0 || length < 2 || length > MODBUS_TCP_MAX_ADU_LENGTH - 6) return -1;
  return bytes.size() >= static_cast<size_t>(6 + length) ? 6 + length : 0;
}

bool IsWrite(int function) { return function == kWriteSingle || function == kWriteMultiple; }

// The request's PDU (after `header` bytes, before a `trailer` of `size`) is
// as long as its function says: libmodbus' modbus_reply reads that many bytes.
bool WellFormed(const uint8_t* query, int size, int header, int trailer) {
  size -= trailer;
  if (size <= header) return false;
  const int function = query[header];
  if (function == kReadHolding || function == kWriteSingle) return size == header + 5;
  if (function == kWriteMultiple)
    return size >= header + 6 && size == header + 6 + query[header + 5];
  return true;  // answered with exception 1 (illegal function) from the header alone
}

}  // namespace

struct ModbusTurntableServer::Impl {
  std::shared_ptr<SimWorld> world;
  SimTurntableController* controller = nullptr;
  ModbusServerOptions options;
  bool tcp = true;
  std::string host;
  int port = 0;
  std::string pty_path;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  int listen_fd = -1;   // TCP
  int pty_master = -1;  // RTU
  int pty_slave = -1;   // RTU: kept open so the master never sees a hang-up
  int stop_fd = -1;     // eventfd that wakes the server thread
  std::vector<TcpClient> clients;
  std::thread thread;
  std::mutex mutex;
  std::deque<PendingFault> faults;
  std::atomic<long> served{0};

  ~Impl() {
    StopThread();
    for (const TcpClient& c : clients) close(c.fd);
    for (int fd : {listen_fd, pty_master, pty_slave, stop_fd}) {
      if (fd >= 0) close(fd);
    }
    if (mapping != nullptr) modbus_mapping_free(mapping);
    if (ctx != nullptr) modbus_free(ctx);
  }

  void StopThread() {
    if (!thread.joinable()) return;
    const uint64_t one = 1;
    (void)!write(stop_fd, &one, sizeof one);
    thread.join();
  }

  Status Setup() {
    const ModbusRegisterMap& m = options.map;
    mapping = modbus_mapping_new(0, 0, m.RegisterSpan(), 0);
    if (mapping == nullptr)
      return Internal(std::string("modbus_mapping_new: ") + modbus_strerror(errno));
    const std::vector<uint16_t> serial = EncodeAscii(options.serial, m.serial_registers);
    std::copy(serial.begin(), serial.end(), mapping->tab_registers + m.serial);
    stop_fd = eventfd(0, EFD_CLOEXEC);
    if (stop_fd < 0) return IoError(std::string("eventfd: ") + std::strerror(errno));
    modbus_set_slave(ctx, options.slave_id);
    return Status::Ok();
  }

  std::optional<PendingFault> TakeFault() {
    std::lock_guard<std::mutex> lock(mutex);
    if (faults.empty()) return std::nullopt;
    PendingFault f = faults.front();
    faults.pop_front();
    return f;
  }

  void Run() {
    for (;;) {
      std::vector<pollfd> fds = {{stop_fd, POLLIN, 0}};
      if (tcp) {
        fds.push_back({listen_fd, POLLIN, 0});
        for (const TcpClient& c : clients) fds.push_back({c.fd, POLLIN, 0});
      } else {
        fds.push_back({pty_master, POLLIN, 0});
      }
      if (poll(fds.data(), fds.size(), -1) < 0) {
        if (errno == EINTR) continue;
        return;
      }
      if (fds[0].revents != 0) return;
      for (size_t i = tcp ? 2 : 1; i < fds.size(); ++i) {
        if (fds[i].revents == 0) continue;
        if (tcp) {
          ReceiveTcp(fds[i].fd);
        } else {
          ReceiveRtu();
        }
      }
      if (tcp && (fds[1].revents & POLLIN) != 0) AcceptAll();
    }
  }

  // Accepts every pending connection. Past kMaxTcpClients the client idle
  // longest goes, preferring one that never sent a request, so that a flood
  // of silent connections cannot exhaust descriptors nor lock a driver out.
  void AcceptAll() {
    for (;;) {
      const int fd = accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
      if (fd < 0) return;
      if (clients.size() >= kMaxTcpClients) DropClient(IdlestClient());
      clients.push_back({fd, {}, false, Clock::now()});
    }
  }

  int IdlestClient() const {
    const TcpClient* idlest = &clients.front();
    for (const TcpClient& c : clients) {
      if (std::pair(c.spoke, c.last_active) < std::pair(idlest->spoke, idlest->last_active))
        idlest = &c;
    }
    return idlest->fd;
  }

  TcpClient* FindClient(int fd) {
    for (TcpClient& c : clients) {
      if (c.fd == fd) return &c;
    }
    return nullptr;
  }

  void DropClient(int fd) {
    close(fd);
    clients.erase(std::remove_if(clients.begin(), clients.end(),
                                 [fd](const TcpClient& c) { return c.fd == fd; }),
                  clients.end());
  }

  // Reads what the client sent, without blocking (libmodbus' modbus_receive
  // select()s, which aborts on a descriptor past FD_SETSIZE), and serves each
  // complete request. A client that sends what cannot be Modbus TCP is dropped.
  void ReceiveTcp(int fd) {
    uint8_t bytes[1024];
    const ssize_t n = recv(fd, bytes, sizeof bytes, MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
    TcpClient* client = FindClient(fd);
    if (client == nullptr) return;
    if (n <= 0) return DropClient(fd);  // closed by the client or broken
    client->pending.insert(client->pending.end(), bytes, bytes + n);
    for (;;) {
      const int size = CompleteTcpFrame(client->pending);
      if (size < 0) return DropClient(fd);
      if (size == 0) return;
      client->spoke = true;
      client->last_active = Clock::now();
      const std::vector<uint8_t> query(client->pending.begin(), client->pending.begin() + size);
      client->pending.erase(client->pending.begin(), client->pending.begin() + size);
      Serve(fd, query.data(), size);
      client = FindClient(fd);  // a fault may have dropped it
      if (client == nullptr) return;
    }
  }

  void ReceiveRtu() {
    modbus_set_socket(ctx, pty_master);
    uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
    const int size = modbus_receive(ctx, query);
    if (size > 0) Serve(pty_master, query, size);  // < 0: a garbled frame; 0: another unit's
  }

  // Serves a request addressed to this unit. Modbus over serial line (V1.02,
  // 2.2): unit 0 is a broadcast, a write every server executes without a
  // reply; the server answers only its own address. Modbus TCP (Messaging
  // Implementation Guide V1.0b, 4.4.1.2) reaches a server by its IP address
  // and has no broadcast: this server answers its own unit id only and
  // ignores any other, 0 included (the client times out, as behind a gateway
  // with no such unit).
  void Serve(int fd, const uint8_t* query, int size) {
    const int h = modbus_get_header_length(ctx);
    if (!WellFormed(query, size, h, tcp ? 0 : kRtuCrcBytes)) return;
    const int unit = query[h - 1];
    const bool broadcast = !tcp && unit == MODBUS_BROADCAST_ADDRESS;
    if (unit != options.slave_id && !broadcast) return;
    if (broadcast && !IsWrite(query[h])) return;
    modbus_set_socket(ctx, fd);
    if (const auto fault = broadcast ? std::nullopt : TakeFault()) {
      InjectInto(fd, *fault, query);
      return;
    }
    Answer(query, size, broadcast);
  }

  void InjectInto(int fd, const PendingFault& f, const uint8_t* query) {
    switch (f.fault) {
      case ModbusServerFault::kNoReply:
        return;
      case ModbusServerFault::kDisconnect:
        if (tcp) DropClient(fd);
        return;
      case ModbusServerFault::kException:
        modbus_reply_exception(ctx, query, static_cast<unsigned>(f.exception_code));
        return;
      case ModbusServerFault::kMalformedReply:
        SendWrongFunction(fd, query);
        return;
    }
  }

  // A well-framed reply whose function code (0x41, with one data byte) does
  // not match the request.
  void SendWrongFunction(int fd, const uint8_t* query) const {
    std::vector<uint8_t> frame;
    if (tcp) {
      frame = {query[0], query[1], 0, 0, 0, 3, query[6], 0x41, 0};
    } else {
      frame = {query[0], 0x41, 0};
      const uint16_t crc = Crc16(frame.data(), frame.size());
      frame.push_back(static_cast<uint8_t>(crc & 0xFF));
      frame.push_back(static_cast<uint8_t>(crc >> 8));
    }
    (void)!write(fd, frame.data(), frame.size());
  }

  // Replies with `exception`, unless the request was a broadcast (no replies).
  void Refuse(const uint8_t* query, unsigned exception, bool broadcast) {
    if (!broadcast) modbus_reply_exception(ctx, query, exception);
  }

  void Answer(const uint8_t* query, int size, bool broadcast) {
    const int h = modbus_get_header_length(ctx);
    const int function = query[h];
    if (function != kReadHolding && !IsWrite(function)) {
      Refuse(query, MODBUS_EXCEPTION_ILLEGAL_FUNCTION, broadcast);
      return;
    }
    const int address = Word(query + h + 1);  // WellFormed: present for these functions
    RefreshStatus();
    if (function == kReadHolding) {
      modbus_reply(ctx, query, size, mapping);
      ++served;
      return;
    }
    const int count = function == kWriteSingle ? 1 : Word(query + h + 3);
    const uint8_t* values = query + h + (function == kWriteSingle ? 3 : 6);
    if (TouchesReadOnly(address, count)) {
      Refuse(query, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS, broadcast);
      return;
    }
    const int command_at = options.map.command - address;
    const bool writes_command = command_at >= 0 && command_at < count;
    if (writes_command && !KnownCommand(Word(values + 2 * command_at))) {
      Refuse(query, MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE, broadcast);
      return;
    }
    // libmodbus sends no reply to an RTU broadcast.
    if (modbus_reply(ctx, query, size, mapping) < 0) return;
    ++served;
    if (writes_command) Execute();
  }

  bool TouchesReadOnly(int address, int count) const {
    const ModbusRegisterMap& m = options.map;
    const std::vector<std::pair<int, int>> read_only = {
        {m.status, 1}, {m.fault_code, 1}, {m.position, 2}, {m.serial, m.serial_registers}};
    for (const auto& [start, n] : read_only) {
      if (address < start + n && start < address + count) return true;
    }
    return false;
  }

  bool KnownCommand(uint16_t code) const {
    const ModbusRegisterMap& m = options.map;
    return code == 0 || code == m.cmd_move_absolute || code == m.cmd_home || code == m.cmd_stop ||
           code == m.cmd_clear_fault;
  }

  int32_t Int32At(int address) const {
    return DecodeInt32(mapping->tab_registers + address, options.map.word_order);
  }

  // Executes the command now in the command register, then clears it.
  void Execute() {
    const ModbusRegisterMap& m = options.map;
    const uint16_t code = mapping->tab_registers[m.command];
    mapping->tab_registers[m.command] = 0;
    if (code == m.cmd_move_absolute) {
      const MotionProfile profile{CountsToDegrees(Int32At(m.speed), m),
                                  CountsToDegrees(Int32At(m.accel), m)};
      controller->StartMove(CountsToDegrees(Int32At(m.target), m), profile);
    } else if (code == m.cmd_home) {
      controller->StartHome();
    } else if (code == m.cmd_stop) {
      controller->Stop();
    } else if (code == m.cmd_clear_fault) {
      controller->ClearFault();
    }
    RefreshStatus();
  }

  void RefreshStatus() {
    const ModbusRegisterMap& m = options.map;
    const TurntableControllerStatus s = controller->Poll();
    uint16_t status = 0;
    const auto set = [&status](bool on, int bit) {
      if (on) status = static_cast<uint16_t>(status | (1u << bit));
    };
    set(s.in_position, m.bit_in_position);
    set(s.homed, m.bit_homed);
    set(s.moving, m.bit_moving);
    set(s.fault != TurntableFaultCode::kNone, m.bit_fault);
    mapping->tab_registers[m.status] = status;
    mapping->tab_registers[m.fault_code] = static_cast<uint16_t>(s.fault);
    const double counts = std::round(s.position_deg * m.counts_per_degree);
    EncodeInt32(static_cast<int32_t>(std::clamp(counts, -2147483648.0, 2147483647.0)), m.word_order,
                mapping->tab_registers + m.position);
  }
};

ModbusTurntableServer::ModbusTurntableServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ModbusTurntableServer::~ModbusTurntableServer() { Stop(); }

Status ModbusServerOptions::Check() const {
  if (slave_id < 1 || slave_id > 247)
    return InvalidArgument("slave_id must lie in 1..247, got " + std::to_string(slave_id));
  if (map.serial_registers < 0 || serial.size() > 2 * static_cast<size_t>(map.serial_registers)) {
    return InvalidArgument("serial " + serial + " does not fit in " +
                           std::to_string(map.serial_registers) + " serial registers");
  }
  if (!(map.counts_per_degree >= 1e-3 && map.counts_per_degree <= 1e7))
    return InvalidArgument("counts_per_degree must lie in [0.001, 1e7]");
  return Status::Ok();
}

Result<std::unique_ptr<ModbusTurntableServer>> ModbusTurntableServer::StartTcp(
    std::shared_ptr<SimWorld> world, ModbusServerOptions options, const std::string& host,
    int port) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("Modbus server"));
  auto impl = std::make_unique<Impl>();
  impl->controller = &WorldTurntableController(*world);
  impl->world = std::move(world);
  impl->options = std::move(options);
  impl->tcp = true;
  impl->host = host;
  impl->ctx = modbus_new_tcp(host.c_str(), port);
  if (impl->ctx == nullptr)
    return InvalidArgument("Modbus server: bad address " + host + ": " + modbus_strerror(errno));
  HR_RETURN_IF_ERROR(impl->Setup());
  impl->listen_fd = modbus_tcp_listen(impl->ctx, kListenBacklog);
  if (impl->listen_fd < 0 || fcntl(impl->listen_fd, F_SETFL, O_NONBLOCK) != 0) {
    return Unavailable("Modbus server: cannot listen on " + host + ":" + std::to_string(port) +
                       ": " + modbus_strerror(errno));
  }
  sockaddr_in bound{};
  socklen_t length = sizeof bound;
  getsockname(impl->listen_fd, reinterpret_cast<sockaddr*>(&bound), &length);
  impl->port = ntohs(bound.sin_port);
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->Run(); });
  return std::unique_ptr<ModbusTurntableServer>(new ModbusTurntableServer(std::move(impl)));
}

Result<std::unique_ptr<ModbusTurntableServer>> ModbusTurntableServer::StartRtu(
    std::shared_ptr<SimWorld> world, ModbusServerOptions options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("Modbus RTU server"));
  auto impl = std::make_unique<Impl>();
  impl->controller = &WorldTurntableController(*world);
  impl->world = std::move(world);
  impl->options = std::move(options);
  impl->tcp = false;
  char name[256] = {};
  if (openpty(&impl->pty_master, &impl->pty_slave, name, nullptr, nullptr) != 0) {
    return Unavailable(std::string("Modbus RTU server: openpty failed: ") + std::strerror(errno));
  }
  impl->pty_path = name;
  if (impl->pty_master >= FD_SETSIZE) {  // libmodbus' modbus_receive select()s on it
    return Unavailable("Modbus RTU server: descriptor " + std::to_string(impl->pty_master) +
                       " is past FD_SETSIZE; this process has too many files open");
  }
  termios raw{};
  tcgetattr(impl->pty_slave, &raw);
  cfmakeraw(&raw);
  tcsetattr(impl->pty_slave, TCSANOW, &raw);
  impl->ctx = modbus_new_rtu(name, 115200, 'N', 8, 1);
  if (impl->ctx == nullptr)
    return Internal(std::string("modbus_new_rtu: ") + modbus_strerror(errno));
  HR_RETURN_IF_ERROR(impl->Setup());
  modbus_set_socket(impl->ctx, impl->pty_master);
  Impl* raw_impl = impl.get();
  impl->thread = std::thread([raw_impl] { raw_impl->Run(); });
  return std::unique_ptr<ModbusTurntableServer>(new ModbusTurntableServer(std::move(impl)));
}

int ModbusTurntableServer::port() const { return impl_->port; }
std::string ModbusTurntableServer::host() const { return impl_->tcp ? impl_->host : ""; }
std::string ModbusTurntableServer::device_path() const { return impl_->pty_path; }

std::string ModbusTurntableServer::Describe() const {
  const std::string unit = " unit " + std::to_string(impl_->options.slave_id);
  if (impl_->tcp) return "modbus tcp " + impl_->host + ":" + std::to_string(impl_->port) + unit;
  return "modbus rtu " + impl_->pty_path + unit;
}

void ModbusTurntableServer::InjectFault(ModbusServerFault fault, int count, int exception_code) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  for (int i = 0; i < count; ++i) impl_->faults.push_back({fault, exception_code});
}

long ModbusTurntableServer::requests_served() const { return impl_->served.load(); }

void ModbusTurntableServer::Stop() {
  if (impl_) impl_->StopThread();
}

}  // namespace hairrig
