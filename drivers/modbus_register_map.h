// The register map of a Modbus turntable controller: where each quantity
// lives, how it is scaled and encoded. The driver (drivers/modbus_turntable.h)
// and the simulated controller (sim_hw/modbus_turntable_server.h) share it, so
// a map written for a real controller also configures its simulation.
//
// All quantities are holding registers (read with function 03, written with
// 16), at 0-based protocol (PDU) addresses; a manual's "4x0001" is address 0.
// The defaults are hairrig's reference profile, written out with comments in
// etc/rig-example.yaml:
//
//   registers:
//     command: 0        # write a command code (below); the controller clears it to 0 when taken
//     status: 1         # status bits (below)
//     fault_code: 2     # 0 none, 1 stall (following error), 2 move beyond limits
//     position: 10      # measured position, 32-bit signed, counts        (2 registers)
//     target: 12        # target of the next move_absolute, 32-bit signed  (2 registers)
//     speed: 14         # move speed, 32-bit unsigned, counts/s            (2 registers)
//     accel: 16         # move acceleration, 32-bit unsigned, counts/s^2   (2 registers)
//     serial: 100       # unit serial number, ASCII, 2 characters per register, high byte first
//     serial_registers: 8
//   counts_per_degree: 1000
//   word_order: high_first  # a 32-bit value's high word at the lower address (or low_first)
//   commands: {move_absolute: 1, home: 2, stop: 3, clear_fault: 4}
//   status_bits: {in_position: 0, homed: 1, moving: 2, fault: 3}
//   limits: {max_speed_deg_s: 90, max_accel_deg_s2: 360, settle_s: 0.3}
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"

namespace hairrig {

enum class WordOrder { kHighFirst, kLowFirst };

struct ModbusRegisterMap {
  int command = 0;
  int status = 1;
  int fault_code = 2;
  int position = 10;
  int target = 12;
  int speed = 14;
  int accel = 16;
  int serial = 100;
  int serial_registers = 8;
  double counts_per_degree = 1000;
  WordOrder word_order = WordOrder::kHighFirst;
  uint16_t cmd_move_absolute = 1;
  uint16_t cmd_home = 2;
  uint16_t cmd_stop = 3;
  uint16_t cmd_clear_fault = 4;
  int bit_in_position = 0;
  int bit_homed = 1;
  int bit_moving = 2;
  int bit_fault = 3;
  double max_speed_deg_s = 90;
  double max_accel_deg_s2 = 360;
  double settle_s = 0.3;

  // The lowest address and the count of registers covering status, fault
  // code, position and target: one read fetches them all.
  int StatusBlockStart() const;
  int StatusBlockCount() const;
  // One past the highest register any field uses.
  int RegisterSpan() const;
};

// Reads the `registers`, `counts_per_degree`, `word_order`, `commands`,
// `status_bits` and `limits` fields of a device's map (each optional, the
// defaults above). Errors name the file, line and field: overlapping
// registers, a bit outside 0..15, a value that does not fit.
Result<ModbusRegisterMap> ParseModbusRegisterMap(const ConfigNode& device);

// A 32-bit value as two registers in `order`, and back.
void EncodeInt32(int32_t value, WordOrder order, uint16_t out[2]);
int32_t DecodeInt32(const uint16_t in[2], WordOrder order);
// Degrees <-> counts (rounded); OutOfRange when the count does not fit 32 bits.
Result<int32_t> DegreesToCounts(double degrees, const ModbusRegisterMap& map);
double CountsToDegrees(int32_t counts, const ModbusRegisterMap& map);
// ASCII, two characters per register (high byte first), NUL-padded; trailing
// NULs and spaces are dropped when decoding.
std::vector<uint16_t> EncodeAscii(const std::string& text, int registers);
std::string DecodeAscii(const uint16_t* registers, int count);

}  // namespace hairrig
