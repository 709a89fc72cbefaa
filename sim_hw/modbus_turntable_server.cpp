#include "sim_hw/modbus_turntable_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <modbus/modbus.h>

#include "sim_hw/sim_turntable_controller.h"

namespace hairrig {

namespace {

constexpr int kReadHolding = 0x03;
constexpr int kWriteSingle = 0x06;
constexpr int kWriteMultiple = 0x10;

uint16_t Word(const uint8_t* bytes) { return static_cast<uint16_t>((bytes[0] << 8) | bytes[1]); }

// Modbus RTU CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF).
uint16_t Crc16(const uint8_t* data, size_t size) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? static_cast<uint16_t>((crc >> 1) ^ 0xA001u) : crc >> 1;
  }
  return crc;
}

struct PendingFault {
  ModbusServerFault fault;
  int exception_code;
};

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
  std::vector<int> clients;
  std::thread thread;
  std::mutex mutex;
  std::deque<PendingFault> faults;
  std::atomic<long> served{0};

  ~Impl() {
    StopThread();
    for (int fd : clients) close(fd);
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
    if (mapping == nullptr) return Internal(std::string("modbus_mapping_new: ") + modbus_strerror(errno));
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
        for (int c : clients) fds.push_back({c, POLLIN, 0});
      } else {
        fds.push_back({pty_master, POLLIN, 0});
      }
      if (poll(fds.data(), fds.size(), -1) < 0) {
        if (errno == EINTR) continue;
        return;
      }
      if (fds[0].revents != 0) return;
      if (tcp && (fds[1].revents & POLLIN) != 0) Accept();
      for (size_t i = tcp ? 2 : 1; i < fds.size(); ++i) {
        if (fds[i].revents != 0) Serve(fds[i].fd);
      }
    }
  }

  void Accept() {
    const int fd = accept(listen_fd, nullptr, nullptr);
    if (fd >= 0) clients.push_back(fd);
  }

  void DropClient(int fd) {
    close(fd);
    clients.erase(std::remove(clients.begin(), clients.end(), fd), clients.end());
  }

  void Serve(int fd) {
    modbus_set_socket(ctx, fd);
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    const int size = modbus_receive(ctx, query);
    if (size < 0) {
      if (tcp) DropClient(fd);  // closed by the client or broken; RTU: a garbled frame is dropped
      return;
    }
    if (size == 0) return;  // addressed to another unit
    if (const auto fault = TakeFault()) {
      InjectInto(fd, *fault, query);
      return;
    }
    Answer(query, size);
  }

  void InjectInto(int fd, const PendingFault& f, const uint8_t* query) {
    switch (f.fault) {
      case ModbusServerFault::kNoReply: return;
      case ModbusServerFault::kDisconnect:
        if (tcp) DropClient(fd);
        return;
      case ModbusServerFault::kException:
        modbus_reply_exception(ctx, query, static_cast<unsigned>(f.exception_code));
        return;
      case ModbusServerFault::kMalformedReply: SendWrongFunction(fd, query); return;
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

  void Answer(const uint8_t* query, int size) {
    const int h = modbus_get_header_length(ctx);
    const int function = query[h];
    const int address = Word(query + h + 1);
    if (function != kReadHolding && function != kWriteSingle && function != kWriteMultiple) {
      modbus_reply_exception(ctx, query, MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
      return;
    }
    RefreshStatus();
    if (function == kReadHolding) {
      modbus_reply(ctx, query, size, mapping);
      ++served;
      return;
    }
    const int count = function == kWriteSingle ? 1 : Word(query + h + 3);
    const uint8_t* values = query + h + (function == kWriteSingle ? 3 : 6);
    if (TouchesReadOnly(address, count)) {
      modbus_reply_exception(ctx, query, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
      return;
    }
    const int command_at = options.map.command - address;
    const bool writes_command = command_at >= 0 && command_at < count;
    if (writes_command && !KnownCommand(Word(values + 2 * command_at))) {
      modbus_reply_exception(ctx, query, MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
      return;
    }
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

  int32_t Int32At(int address) const { return DecodeInt32(mapping->tab_registers + address, options.map.word_order); }

  // Executes the command now in the command register, then clears it.
  void Execute() {
    const ModbusRegisterMap& m = options.map;
    const uint16_t code = mapping->tab_registers[m.command];
    mapping->tab_registers[m.command] = 0;
    if (code == m.cmd_move_absolute) {
      const MotionProfile profile{CountsToDegrees(Int32At(m.speed), m), CountsToDegrees(Int32At(m.accel), m)};
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

Result<std::unique_ptr<ModbusTurntableServer>> ModbusTurntableServer::StartTcp(std::shared_ptr<SimWorld> world,
                                                                             ModbusServerOptions options,
                                                                             const std::string& host, int port) {
  auto impl = std::make_unique<Impl>();
  impl->controller = &WorldTurntableController(*world);
  impl->world = std::move(world);
  impl->options = std::move(options);
  impl->tcp = true;
  impl->host = host;
  impl->ctx = modbus_new_tcp(host.c_str(), port);
  if (impl->ctx == nullptr) return InvalidArgument("Modbus server: bad address " + host + ": " + modbus_strerror(errno));
  HR_RETURN_IF_ERROR(impl->Setup());
  impl->listen_fd = modbus_tcp_listen(impl->ctx, 8);
  if (impl->listen_fd < 0) {
    return Unavailable("Modbus server: cannot listen on " + host + ":" + std::to_string(port) + ": " +
                       modbus_strerror(errno));
  }
  sockaddr_in bound{};
  socklen_t length = sizeof bound;
  getsockname(impl->listen_fd, reinterpret_cast<sockaddr*>(&bound), &length);
  impl->port = ntohs(bound.sin_port);
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->Run(); });
  return std::unique_ptr<ModbusTurntableServer>(new ModbusTurntableServer(std::move(impl)));
}

Result<std::unique_ptr<ModbusTurntableServer>> ModbusTurntableServer::StartRtu(std::shared_ptr<SimWorld> world,
                                                                             ModbusServerOptions options) {
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
  termios raw{};
  tcgetattr(impl->pty_slave, &raw);
  cfmakeraw(&raw);
  tcsetattr(impl->pty_slave, TCSANOW, &raw);
  impl->ctx = modbus_new_rtu(name, 115200, 'N', 8, 1);
  if (impl->ctx == nullptr) return Internal(std::string("modbus_new_rtu: ") + modbus_strerror(errno));
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
