#include "drivers/modbus_turntable.h"

#include <cmath>
#include <string>

#include "drivers/polled_turntable.h"

namespace hairrig {

namespace {

bool Bit(uint16_t word, int bit) { return ((word >> bit) & 1u) != 0; }

class ModbusTurntable : public PolledTurntable {
 public:
  ModbusTurntable(const DeviceInfo& info, ModbusTurntableOptions options)
      : PolledTurntable(info), options_(std::move(options)), link_(options_.endpoint) {}

  const ModbusLink& link() const { return link_; }
  double time_scale() const override { return options_.time_scale; }

  TurntableCapabilities capabilities() const override {
    return {.max_speed_deg_s = options_.map.max_speed_deg_s,
            .max_accel_deg_s2 = options_.map.max_accel_deg_s2,
            .resolution_deg = 1.0 / options_.map.counts_per_degree,
            .can_home = true,
            .settle_s = options_.map.settle_s};
  }

 protected:
  // Clears a fault latched by the controller.
  Status DoOpen() override {
    HR_RETURN_IF_ERROR(Fail(link_.Connect()));
    HR_RETURN_IF_ERROR(CheckSerial());
    HR_ASSIGN_OR_RETURN(const Registers r, ReadRegisters());
    if (Bit(r.status, options_.map.bit_fault)) {
      HR_RETURN_IF_ERROR(Fail(Command(options_.map.cmd_clear_fault)));
    }
    SetState(DeviceState::kReady);
    return Status::Ok();
  }

  Status DoClose() override {
    link_.Disconnect();
    return Status::Ok();
  }

  Status DoHealthCheck() override { return ReadRegisters().status(); }

  Status DoHome(std::chrono::milliseconds timeout) override {
    HR_RETURN_IF_ERROR(Fail(Command(options_.map.cmd_home)));
    MoveStarted(0);
    return Wait(timeout, /*need_homed=*/true);
  }

  Status DoStartMove(double target_deg, const MotionProfile& p) override {
    HR_RETURN_IF_ERROR(CheckMoveRequest(Describe(), target_deg, p, capabilities()));
    const ModbusRegisterMap& m = options_.map;
    auto target = DegreesToCounts(target_deg, m);
    if (!target.ok()) return target.status().WithContext(Describe());
    std::vector<uint16_t> words(8, 0);
    EncodeInt32(target.value(), m.word_order, &words[0]);
    EncodeInt32(static_cast<int32_t>(std::lround(p.speed_deg_s * m.counts_per_degree)),
                m.word_order, &words[2]);
    EncodeInt32(static_cast<int32_t>(std::lround(p.accel_deg_s2 * m.counts_per_degree)),
                m.word_order, &words[4]);
    HR_RETURN_IF_ERROR(Fail(WritePair(m.target, &words[0])));
    HR_RETURN_IF_ERROR(Fail(WritePair(m.speed, &words[2])));
    HR_RETURN_IF_ERROR(Fail(WritePair(m.accel, &words[4])));
    HR_RETURN_IF_ERROR(Fail(Command(m.cmd_move_absolute)));
    MoveStarted(target_deg);
    return Status::Ok();
  }

  Result<TurntableStatus> DoReadStatus() override {
    HR_ASSIGN_OR_RETURN(const Registers r, ReadRegisters());
    const ModbusRegisterMap& m = options_.map;
    TurntableStatus s{.position_deg = CountsToDegrees(r.position, m),
                      .target_deg = target_deg(),
                      .moving = Bit(r.status, m.bit_moving),
                      .in_position = Bit(r.status, m.bit_in_position),
                      .homed = Bit(r.status, m.bit_homed),
                      .fault = Bit(r.status, m.bit_fault)};
    if (s.in_position && !s.fault && state() == DeviceState::kBusy) SetState(DeviceState::kReady);
    return s;
  }

  Status DoWaitInPosition(std::chrono::milliseconds timeout) override {
    return Wait(timeout, /*need_homed=*/false);
  }

  Status DoStop() override {
    StopRequested();
    return Command(options_.map.cmd_stop).WithContext(Describe() + ": stop");
  }

 private:
  struct Registers {
    uint16_t status = 0;
    uint16_t fault_code = 0;
    int32_t position = 0;
  };

  // Marks the device faulted on an I/O failure, passing success through.
  Status Fail(const Status& s) { return s.ok() ? s : Fault(s); }

  Status Command(uint16_t code) { return link_.Write(options_.map.command, {code}); }
  Status WritePair(int address, const uint16_t* pair) {
    return link_.Write(address, {pair[0], pair[1]});
  }

  Result<Registers> ReadRegisters() {
    const ModbusRegisterMap& m = options_.map;
    const int start = m.StatusBlockStart();
    auto block = link_.Read(start, m.StatusBlockCount());
    if (!block.ok()) return Fault(block.status());
    const std::vector<uint16_t>& b = block.value();
    Registers r;
    r.status = b[static_cast<size_t>(m.status - start)];
    r.fault_code = b[static_cast<size_t>(m.fault_code - start)];
    r.position = DecodeInt32(&b[static_cast<size_t>(m.position - start)], m.word_order);
    return r;
  }

  Status CheckSerial() {
    auto words = link_.Read(options_.map.serial, options_.map.serial_registers);
    if (!words.ok()) return Fault(words.status());
    const std::string found = DecodeAscii(words.value().data(), options_.map.serial_registers);
    if (found == info().serial) return Status::Ok();
    link_.Disconnect();
    return Fault(
        Unavailable("the controller at " + options_.endpoint.Describe() + " reports serial '" +
                    found + "', not '" + info().serial +
                    "': check the address (or the cable) and the serial in the rig config"));
  }

  // Polls the status registers until in position (and homed when asked).
  Status Wait(std::chrono::milliseconds timeout, bool need_homed) {
    const ModbusRegisterMap& m = options_.map;
    return WaitUntilDone(
        timeout, std::chrono::milliseconds(options_.poll_ms), [&]() -> Result<MotionPoll> {
          HR_ASSIGN_OR_RETURN(const Registers r, ReadRegisters());
          MotionPoll p;
          p.position_deg = CountsToDegrees(r.position, m);
          if (Bit(r.status, m.bit_fault)) {
            p.fault = "fault code " + std::to_string(r.fault_code) +
                      " (reference profile: 1 stall, 2 limits)";
          }
          p.done = Bit(r.status, m.bit_in_position) && !Bit(r.status, m.bit_moving) &&
                   (!need_homed || Bit(r.status, m.bit_homed));
          return p;
        });
  }

  ModbusTurntableOptions options_;
  ModbusLink link_;
};

}  // namespace

Result<ModbusTurntableOptions> ParseModbusTurntableOptions(const ConfigNode& device) {
  device.AllowOnlyKeys({"name",
                        "backend",
                        "serial",
                        "transport",
                        "host",
                        "port",
                        "device",
                        "baud",
                        "parity",
                        "data_bits",
                        "stop_bits",
                        "slave_id",
                        "timeout_ms",
                        "retries",
                        "poll_ms",
                        "registers",
                        "counts_per_degree",
                        "word_order",
                        "commands",
                        "status_bits",
                        "limits"});
  ModbusTurntableOptions options;
  HR_ASSIGN_OR_RETURN(options.endpoint, ParseModbusEndpoint(device));
  HR_ASSIGN_OR_RETURN(options.map, ParseModbusRegisterMap(device));
  options.poll_ms = device.Integer("poll_ms", options.poll_ms, {.min = 1, .max = 1000});
  if (!device.ok()) return device.status();
  return options;
}

Status ModbusTurntableOptions::Check() const {
  HR_RETURN_IF_ERROR(endpoint.Check());
  if (!(map.counts_per_degree >= 1e-3 && map.counts_per_degree <= 1e7))
    return InvalidArgument("counts_per_degree must lie in [0.001, 1e7]");
  if (!(map.max_speed_deg_s > 0) || !std::isfinite(map.max_speed_deg_s))
    return InvalidArgument("limits.max_speed_deg_s must be finite and positive");
  if (!(map.max_accel_deg_s2 > 0) || !std::isfinite(map.max_accel_deg_s2))
    return InvalidArgument("limits.max_accel_deg_s2 must be finite and positive");
  if (!(map.settle_s >= 0 && map.settle_s <= 60))
    return InvalidArgument("limits.settle_s must lie in [0, 60] s");
  if (poll_ms < 1 || poll_ms > 1000)
    return InvalidArgument("poll_ms must lie in 1..1000, got " + std::to_string(poll_ms));
  if (!(time_scale > 0) || !std::isfinite(time_scale))
    return InvalidArgument("time_scale must be finite and positive");
  return Status::Ok();
}

std::unique_ptr<Turntable> MakeModbusTurntable(const DeviceInfo& info,
                                               ModbusTurntableOptions options) {
  return std::make_unique<ModbusTurntable>(info, std::move(options));
}

ModbusLinkStats ModbusTurntableLinkStats(const Turntable& turntable) {
  const auto* modbus = dynamic_cast<const ModbusTurntable*>(&turntable);
  return modbus != nullptr ? modbus->link().stats() : ModbusLinkStats{};
}

void RegisterModbusTurntableBackend(DeviceRegistry* registry, ModbusOptionsHook hook) {
  registry->AddBackend<Turntable>(
      DeviceKind::kTurntable, "modbus",
      [hook](const DeviceConfig& c) -> Result<std::unique_ptr<Turntable>> {
        HR_ASSIGN_OR_RETURN(ModbusTurntableOptions options, ParseModbusTurntableOptions(c.node));
        if (hook) HR_RETURN_IF_ERROR(hook(c, &options));
        HR_RETURN_IF_ERROR(options.Check().WithContext("turntable " + c.name));
        const DeviceInfo info =
            c.Info("Modbus turntable controller (" + options.endpoint.Describe() + ")");
        return MakeModbusTurntable(info, std::move(options));
      });
}

}  // namespace hairrig
