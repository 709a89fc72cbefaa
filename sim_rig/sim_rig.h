// The simulated rig's plug point (rig/rig_extension.h). Once RegisterSimRig
// has run, the rig configs this process loads may have a `sim` section, and
// the rigs it builds from them are simulated; production code (rig/ and the
// drivers) does not include sim_hw/.
//
// Config (top level):
//   sim:
//     scene: scenes/default.yaml  (required; relative to the config's folder,
//                                  RigConfig::relative_to)
//     time_scale: 0.01            (simulated device timings x this; 1 = real time)
//     faults: [...]               (sim_hw/sim_faults.h)
//
// A rig built from a config with a `sim` section has a simulated world
// (sim_hw/sim_devices.h) rendering the scene: the `sim` backend of every device
// kind acts on it; its captures are written to the world's disk (a `disk_full`
// fault); each capture's ground truth (sim_hw/capture_truth.h) is written under
// <capture>/ground_truth/ by a capture observer, through the capture's storage
// and its storage.min_free_mb check (rig/capture.h CaptureFolder). The real
// backends reach simulated peers of the world:
//   - a `modbus` turntable with `host: sim` (TCP) or `device: sim` (RTU) talks
//     to a simulated controller served on loopback or a pseudo-terminal
//     (sim_hw/modbus_turntable_server.h);
//   - a `gphoto2` camera with `port: sim` is a simulated DSLR
//     (sim_hw/sim_dslr_server.h) rendering the scene camera with its serial,
//     reached through the project's camlib (CAMLIBS is set for this process);
//   - an `aravis` camera with `address: sim` is Aravis' in-process fake camera
//     rendering that scene camera (sim_hw/sim_aravis.h);
//   - a `v4l2` camera with `device: sim` is a fake UVC camera behind the
//     backend's system-call layer (sim_hw/sim_v4l2.h);
//   - a `usbrelay` light with `bus: sim` is a channel of a simulated relay
//     board (its `board` id, 8 channels; sim_hw/sim_usb_relay.h) powering the
//     scene light `light` (default: the device's name).
// Those values in a config without a `sim` section are refused, naming the field.
// RegisterSimRig also registers the scene renderer as the strand previewer
// (rig/simulation_preview.h) of `hairrig simulate`.
#pragma once

#include <memory>
#include <vector>

#include "rig/rig_config.h"

namespace hairrig {

class ModbusTurntableServer;  // sim_hw/modbus_turntable_server.h
class SimAravisFeed;          // sim_hw/sim_aravis.h
class SimDslrServer;          // sim_hw/sim_dslr_server.h
class SimUsbRelayBus;         // sim_hw/sim_usb_relay.h
class SimWorld;               // sim_hw/sim_devices.h

// Registers the simulated rig (RegisterRigExtension). Idempotent, thread-safe.
void RegisterSimRig();

// What the simulated rig serves for one rig (one of Rig::extension_states).
struct SimRigState : RigExtensionState {
  SimRigState();
  ~SimRigState() override;

  std::shared_ptr<SimWorld> world;  // null without a `sim` section
  // Protocol-level simulators the rig's devices talk to (declared after
  // `world`, so they are stopped before it goes).
  std::vector<std::unique_ptr<ModbusTurntableServer>> modbus_servers;
  std::vector<std::unique_ptr<SimDslrServer>> dslr_servers;
  std::vector<std::unique_ptr<SimAravisFeed>> aravis_feeds;
  std::shared_ptr<SimUsbRelayBus> relay_bus;  // the boards of `usbrelay` lights with bus: sim
};

// The simulated rig's state in `rig`; null for a rig built without it.
const SimRigState* FindSimRigState(const Rig& rig);

}  // namespace hairrig
