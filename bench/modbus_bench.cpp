// Modbus round trip between the `modbus` driver's link and the simulated
// controller (a libmodbus server), over TCP on loopback and RTU over a
// pseudo-terminal pair. Run from the repository root:
//   build/bench/hairrig_modbus_bench
#include <benchmark/benchmark.h>

#include "drivers/modbus_link.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/scene.h"

namespace hairrig {
namespace {

struct Peer {
  std::shared_ptr<SimWorld> world;
  std::unique_ptr<ModbusTurntableServer> server;
  std::unique_ptr<ModbusLink> link;
};

Peer Connect(bool tcp, benchmark::State& state) {
  Peer p;
  auto scene = LoadScene("etc/scenes/default.yaml");
  if (!scene.ok()) state.SkipWithError(scene.status().ToString().c_str());
  p.world = CreateSimWorld(*scene, {}).value();
  const ModbusServerOptions options{ModbusRegisterMap{}, "SIM-TT-0001", 1};
  p.server = (tcp ? ModbusTurntableServer::StartTcp(p.world, options)
                  : ModbusTurntableServer::StartRtu(p.world, options))
                 .value();
  ModbusEndpoint e;
  if (tcp) {
    e.port = p.server->port();
  } else {
    e.transport = ModbusEndpoint::Transport::kRtu;
    e.device = p.server->device_path();
    e.baud = 115200;
  }
  p.link = std::make_unique<ModbusLink>(e);
  if (!p.link->Connect().ok()) state.SkipWithError("cannot connect");
  return p;
}

// One status poll: the 17-register block a waiting driver reads every poll_ms.
void BM_ModbusStatusRead(benchmark::State& state) {
  Peer p = Connect(state.range(0) == 0, state);
  const ModbusRegisterMap map;
  for (auto _ : state) {
    auto block = p.link->Read(map.StatusBlockStart(), map.StatusBlockCount());
    if (!block.ok()) state.SkipWithError(block.status().ToString().c_str());
    benchmark::DoNotOptimize(block);
  }
  state.SetLabel(state.range(0) == 0 ? "tcp loopback" : "rtu pty");
}
BENCHMARK(BM_ModbusStatusRead)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// Writing a move's target, speed and acceleration (function 16, 6 registers).
void BM_ModbusWriteMoveParameters(benchmark::State& state) {
  Peer p = Connect(state.range(0) == 0, state);
  const ModbusRegisterMap map;
  const std::vector<uint16_t> words = {0, 45000, 0, 60000, 3, 41248};
  for (auto _ : state) {
    const Status s = p.link->Write(map.target, words);
    if (!s.ok()) state.SkipWithError(s.ToString().c_str());
  }
  state.SetLabel(state.range(0) == 0 ? "tcp loopback" : "rtu pty");
}
BENCHMARK(BM_ModbusWriteMoveParameters)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hairrig

BENCHMARK_MAIN();
