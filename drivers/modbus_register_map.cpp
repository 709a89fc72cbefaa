#include "drivers/modbus_register_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

namespace hairrig {

namespace {

struct RegisterField {
  const char* name;
  int* address;
  int count;
};

std::vector<RegisterField> Fields(ModbusRegisterMap& m) {
  return {{"command", &m.command, 1},       {"status", &m.status, 1},
          {"fault_code", &m.fault_code, 1}, {"position", &m.position, 2},
          {"target", &m.target, 2},         {"speed", &m.speed, 2},
          {"accel", &m.accel, 2},           {"serial", &m.serial, m.serial_registers}};
}

void ReadRegisters(const ConfigNode& node, ModbusRegisterMap* map) {
  node.AllowOnlyKeys({"command", "status", "fault_code", "position", "target", "speed", "accel",
                      "serial", "serial_registers"});
  map->serial_registers =
      node.Integer("serial_registers", map->serial_registers, {.min = 1, .max = 32});
  for (RegisterField& f : Fields(*map))
    *f.address = node.Integer(f.name, *f.address, {.min = 0, .max = 65535 - 32});
  if (!node.ok()) return;
  const std::vector<RegisterField> fields = Fields(*map);
  for (size_t i = 0; i < fields.size(); ++i) {
    for (size_t j = i + 1; j < fields.size(); ++j) {
      const RegisterField& a = fields[i];
      const RegisterField& b = fields[j];
      if (*a.address < *b.address + b.count && *b.address < *a.address + a.count) {
        node.Fail(b.name,
                  std::string("registers of '") + b.name + "' overlap those of '" + a.name + "'");
        return;
      }
    }
  }
}

uint16_t Code(const ConfigNode& node, const char* key, uint16_t fallback) {
  return static_cast<uint16_t>(node.Integer(key, fallback, {.min = 1, .max = 65535}));
}

void ReadCommands(const ConfigNode& node, ModbusRegisterMap* m) {
  node.AllowOnlyKeys({"move_absolute", "home", "stop", "clear_fault"});
  m->cmd_move_absolute = Code(node, "move_absolute", m->cmd_move_absolute);
  m->cmd_home = Code(node, "home", m->cmd_home);
  m->cmd_stop = Code(node, "stop", m->cmd_stop);
  m->cmd_clear_fault = Code(node, "clear_fault", m->cmd_clear_fault);
  const std::vector<uint16_t> codes = {m->cmd_move_absolute, m->cmd_home, m->cmd_stop,
                                       m->cmd_clear_fault};
  if (node.ok() && std::set<uint16_t>(codes.begin(), codes.end()).size() != codes.size()) {
    node.Fail("", "two commands share one code");
  }
}

void ReadStatusBits(const ConfigNode& node, ModbusRegisterMap* m) {
  node.AllowOnlyKeys({"in_position", "homed", "moving", "fault"});
  m->bit_in_position = node.Integer("in_position", m->bit_in_position, {.min = 0, .max = 15});
  m->bit_homed = node.Integer("homed", m->bit_homed, {.min = 0, .max = 15});
  m->bit_moving = node.Integer("moving", m->bit_moving, {.min = 0, .max = 15});
  m->bit_fault = node.Integer("fault", m->bit_fault, {.min = 0, .max = 15});
  const std::vector<int> bits = {m->bit_in_position, m->bit_homed, m->bit_moving, m->bit_fault};
  if (node.ok() && std::set<int>(bits.begin(), bits.end()).size() != bits.size()) {
    node.Fail("", "two status flags share one bit");
  }
}

// The controller's limits, in the ranges the capture plan's motion takes
// (core/config.h kTurntableSpeedRange, kTurntableAccelRange).
void ReadLimits(const ConfigNode& node, ModbusRegisterMap* m) {
  node.AllowOnlyKeys({"max_speed_deg_s", "max_accel_deg_s2", "settle_s"});
  m->max_speed_deg_s = node.Number("max_speed_deg_s", m->max_speed_deg_s, kTurntableSpeedRange);
  m->max_accel_deg_s2 = node.Number("max_accel_deg_s2", m->max_accel_deg_s2, kTurntableAccelRange);
  m->settle_s = node.Number("settle_s", m->settle_s, {.min = 0, .max = 60});
}

}  // namespace

int ModbusRegisterMap::StatusBlockStart() const {
  return std::min({status, fault_code, position, target});
}

int ModbusRegisterMap::StatusBlockCount() const {
  return std::max({status + 1, fault_code + 1, position + 2, target + 2}) - StatusBlockStart();
}

int ModbusRegisterMap::RegisterSpan() const {
  ModbusRegisterMap copy = *this;
  int span = 0;
  for (const RegisterField& f : Fields(copy)) span = std::max(span, *f.address + f.count);
  return span;
}

Result<ModbusRegisterMap> ParseModbusRegisterMap(const ConfigNode& device) {
  ModbusRegisterMap map;
  if (device.Has("registers")) ReadRegisters(device.Child("registers"), &map);
  map.counts_per_degree =
      device.Number("counts_per_degree", map.counts_per_degree, {.min = 1e-3, .max = 1e7});
  map.word_order =
      device.Choice("word_order", {"high_first", "low_first"}, "high_first") == "low_first"
          ? WordOrder::kLowFirst
          : WordOrder::kHighFirst;
  if (device.Has("commands")) ReadCommands(device.Child("commands"), &map);
  if (device.Has("status_bits")) ReadStatusBits(device.Child("status_bits"), &map);
  if (device.Has("limits")) ReadLimits(device.Child("limits"), &map);
  if (!device.ok()) return device.status();
  if (map.StatusBlockCount() > 125) {
    device.Fail("registers",
                "status, fault_code, position and target must lie within 125 registers (one read)");
    return device.status();
  }
  return map;
}

void EncodeInt32(int32_t value, WordOrder order, uint16_t out[2]) {
  const auto bits = static_cast<uint32_t>(value);
  const auto high = static_cast<uint16_t>(bits >> 16);
  const auto low = static_cast<uint16_t>(bits & 0xFFFFu);
  out[0] = order == WordOrder::kHighFirst ? high : low;
  out[1] = order == WordOrder::kHighFirst ? low : high;
}

int32_t DecodeInt32(const uint16_t in[2], WordOrder order) {
  const uint32_t high = order == WordOrder::kHighFirst ? in[0] : in[1];
  const uint32_t low = order == WordOrder::kHighFirst ? in[1] : in[0];
  return static_cast<int32_t>((high << 16) | low);
}

Result<int32_t> DegreesToCounts(double degrees, const ModbusRegisterMap& map) {
  const double counts = std::round(degrees * map.counts_per_degree);
  if (!std::isfinite(counts) || counts < std::numeric_limits<int32_t>::min() ||
      counts > std::numeric_limits<int32_t>::max()) {
    return OutOfRange(std::to_string(degrees) + " deg is " + std::to_string(counts) +
                      " counts, beyond a 32-bit register pair (counts_per_degree " +
                      std::to_string(map.counts_per_degree) + ")");
  }
  return static_cast<int32_t>(counts);
}

double CountsToDegrees(int32_t counts, const ModbusRegisterMap& map) {
  return counts / map.counts_per_degree;
}

std::vector<uint16_t> EncodeAscii(const std::string& text, int registers) {
  std::vector<uint16_t> out(static_cast<size_t>(registers), 0);
  for (size_t i = 0; i < text.size() && i / 2 < out.size(); ++i) {
    const auto byte = static_cast<uint16_t>(static_cast<unsigned char>(text[i]));
    out[i / 2] |= (i % 2 == 0) ? static_cast<uint16_t>(byte << 8) : byte;
  }
  return out;
}

std::string DecodeAscii(const uint16_t* registers, int count) {
  std::string text;
  for (int i = 0; i < count; ++i) {
    text.push_back(static_cast<char>(registers[i] >> 8));
    text.push_back(static_cast<char>(registers[i] & 0xFF));
  }
  while (!text.empty() && (text.back() == '\0' || text.back() == ' ')) text.pop_back();
  return text;
}

}  // namespace hairrig
