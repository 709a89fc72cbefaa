// `hairrig sim serve`: the protocol-level simulators of a scene, served for
// outside tools (mbpoll, gphoto2, Aravis' tools) until SIGINT or SIGTERM:
//   - a Modbus TCP turntable controller on 127.0.0.1 (the register map of
//     etc/rig-example.yaml) and, optionally, the same over Modbus RTU on a
//     pseudo-terminal (sim_hw/modbus_turntable_server.h);
//   - one simulated DSLR per scene camera, rendering that camera's view,
//     reached through the project's libgphoto2 camlib (sim_hw/sim_dslr_server.h);
//   - Aravis' GigE Vision fake camera rendering the scene's last camera on
//     127.0.0.1:3956, one per machine at a time (sim_hw/sim_aravis.h).
#pragma once

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct SimServeOptions {
  std::string scene_file;                        // the scene (sim_hw/scene.h)
  std::string turntable_serial = "SIM-TT-0001";  // written to the controller's serial registers
  int modbus_port = 0;                           // TCP port on 127.0.0.1, 0-65535; 0: a free one
  int slave_id = 1;                              // Modbus unit id, 1-247
  double time_scale = 1.0;  // device seconds x this = wall seconds; > 0 (1: real time)
  bool rtu = true;          // Modbus RTU on a pseudo-terminal too
  bool dslr = true;         // the simulated DSLRs
  bool gige = true;         // the GigE Vision fake camera
  // Called on the calling thread once every simulator serves, with how an
  // outside tool reaches each: lines, each ending in "\n".
  std::function<void(const std::string& endpoints)> on_serving;

  // InvalidArgument naming the field and its range.
  Status Check() const;
};

struct SimServeSummary {
  struct Modbus {
    std::string endpoint;  // ModbusTurntableServer::Describe()
    long requests_served = 0;
  };
  struct Dslr {
    std::string serial;
    std::string port;  // the gphoto2 port, "disk:<folder>"
    int shots = 0;
  };
  struct GigE {
    std::string serial;
    std::string address;
    int frames = 0;  // rendered
  };
  std::string stopped_by;      // "SIGINT" or "SIGTERM"
  std::vector<Modbus> modbus;  // TCP, then RTU
  std::vector<Dslr> dslr;
  std::optional<GigE> gige;

  // stopped_by, modbus, dslr, gige (null when not served).
  nlohmann::json ToJson() const;
  std::string BriefReport() const;
};

// Blocks SIGINT and SIGTERM in the calling thread before any simulator's
// thread starts (the threads inherit the mask), serves until one of them
// arrives (sigwait), stops every simulator and restores the thread's signal
// mask. Errors: the options, the scene (named), a simulator that cannot start
// (its port taken, the camlib not built).
Result<SimServeSummary> ServeSimulatedDevices(const SimServeOptions& options);

}  // namespace hairrig
