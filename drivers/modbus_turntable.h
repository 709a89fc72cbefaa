// The `modbus` turntable backend: a stepper/servo controller reached over
// Modbus TCP or RTU (RS-485), driven through the register map of
// drivers/modbus_register_map.h.
//
// Rig config (devices.turntable), every field but the first three optional:
//   {name: turntable, backend: modbus, serial: TT-00042,
//    transport: tcp, host: 192.168.10.20, port: 502,          # or
//    transport: rtu, device: /dev/serial/by-id/usb-FTDI_...-port0, baud: 19200, parity: even,
//    data_bits: 8, stop_bits: 1,
//    slave_id: 1, timeout_ms: 500, retries: 2, poll_ms: 10,
//    registers: {...}, counts_per_degree: 1000, word_order: high_first,
//    commands: {...}, status_bits: {...}, limits: {...}}
// The unit is identified by the serial number in its serial registers: Open()
// refuses a controller whose serial differs from the config's (a swapped
// cable or a wrong address), naming both.
//
// Open() clears a fault latched by the controller (the recovery from the
// faulted state). Timeouts, malformed replies and lost connections are
// retried and reconnected by drivers/modbus_link.h; what still fails marks
// the turntable faulted with the link's message.
#pragma once

#include <functional>
#include <memory>

#include "drivers/modbus_link.h"
#include "drivers/modbus_register_map.h"
#include "drivers/registry.h"

namespace hairrig {

struct ModbusTurntableOptions {
  ModbusEndpoint endpoint;
  ModbusRegisterMap map;
  int poll_ms = 10;  // status polling period while waiting for a move
  double time_scale =
      1.0;  // wall s per device s: 1 for real hardware (a simulated controller sets its own)

  // InvalidArgument naming the config field for a value out of the range
  // ParseModbusTurntableOptions accepts (the hook's rewrites included):
  // the endpoint's fields, counts_per_degree, limits.*, poll_ms, time_scale.
  Status Check() const;
};

// Every field of the device's map, with errors naming the file, line and field.
Result<ModbusTurntableOptions> ParseModbusTurntableOptions(const ConfigNode& device);

std::unique_ptr<Turntable> MakeModbusTurntable(const DeviceInfo& info,
                                               ModbusTurntableOptions options);
// The link statistics of a turntable made by MakeModbusTurntable (requests,
// retries, reconnects); zeros for any other turntable.
ModbusLinkStats ModbusTurntableLinkStats(const Turntable& turntable);

// Called with the parsed options before the device is made; may rewrite them
// (the rig points a device at the simulated controller it starts).
using ModbusOptionsHook = std::function<Status(const DeviceConfig&, ModbusTurntableOptions*)>;
// Registers the `modbus` turntable backend.
void RegisterModbusTurntableBackend(DeviceRegistry* registry, ModbusOptionsHook hook = nullptr);

}  // namespace hairrig
