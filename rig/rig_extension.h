// The rig's extension point: code outside the production rig plugs into every
// rig config this process loads and every rig it builds, without rig/ knowing
// it. The simulated rig (sim_rig/sim_rig.h) is one: it reads the config's `sim`
// section, registers the `sim` backend, serves simulated peers that the real
// backends talk to and writes each capture's ground truth.
//
// LoadRigConfig allows the top-level sections the registered extensions claim
// and has each extension check them; BuildRig attaches each registered
// extension, in registration order, before it builds the devices (unless
// RigBuildOptions::attach_extensions is false).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "drivers/aravis_camera.h"
#include "drivers/gphoto2_camera.h"
#include "drivers/modbus_turntable.h"
#include "drivers/registry.h"
#include "drivers/usb_relay.h"
#include "drivers/v4l2_camera.h"
#include "rig/rig_config.h"

namespace hairrig {

// Hooks the real backends run, in order, on a device's parsed options before
// the device is built. Each hook leaves the options of devices it does not
// serve alone, may rewrite the others (point an endpoint at a peer it serves),
// and may fail: BuildRig then returns its error.
struct RigBackendHooks {
  std::vector<ModbusOptionsHook> modbus;
  std::vector<Gphoto2OptionsHook> gphoto2;
  std::vector<AravisOptionsHook> aravis;
  std::vector<V4l2OptionsHook> v4l2;
  std::vector<UsbRelayOptionsHook> usb_relay;
  // Fields of a `usbrelay` light's map that the usb_relay hooks read.
  std::vector<std::string> usb_relay_fields;
};

// What an extension attaches to while BuildRig runs (no device built yet).
struct RigAssembly {
  const RigConfig& config;
  // Extensions add their state (Rig::extension_states: whatever they start,
  // kept as long as the rig's devices live), capture observers and capture
  // storage.
  Rig& rig;
  DeviceRegistry& registry;  // extensions add the backends they provide
  RigBackendHooks& hooks;
};

class RigExtension {
 public:
  virtual ~RigExtension() = default;
  // Top-level sections of the rig config this extension reads ("sim").
  virtual std::vector<std::string> ConfigSections() const = 0;
  // Checks the extension's sections of a config being loaded (absent ones
  // included); errors name the file, line and field.
  virtual Status CheckConfig(const RigConfig& config) const = 0;
  // Adds the extension's backends, hooks, state and observers to a rig being
  // built from `assembly.config`; an error fails BuildRig.
  virtual Status Attach(RigAssembly& assembly) const = 0;
};

// Adds `extension` to those every LoadRigConfig and BuildRig of this process
// use, after those registered before it; an extension already registered is
// not added twice. Thread-safe.
void RegisterRigExtension(std::shared_ptr<const RigExtension> extension);
// The registered extensions, in registration order.
std::vector<std::shared_ptr<const RigExtension>> RegisteredRigExtensions();

}  // namespace hairrig
