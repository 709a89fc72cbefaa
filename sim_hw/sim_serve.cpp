#include "sim_hw/sim_serve.h"

#include <pthread.h>
#include <signal.h>

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/string_format.h"
#include "sim_hw/modbus_turntable_server.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_protocol.h"
#include "sim_hw/sim_dslr_server.h"

namespace hairrig {

namespace {

// SIGINT and SIGTERM blocked in this thread for the guard's lifetime, the
// previous mask restored after.
class StopSignalsBlocked {
 public:
  StopSignalsBlocked() {
    sigemptyset(&signals_);
    sigaddset(&signals_, SIGINT);
    sigaddset(&signals_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals_, &previous_);
  }
  ~StopSignalsBlocked() { pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }
  StopSignalsBlocked(const StopSignalsBlocked&) = delete;
  StopSignalsBlocked& operator=(const StopSignalsBlocked&) = delete;

  // Waits for one of them; its name.
  std::string Wait() const {
    int signal = 0;
    sigwait(&signals_, &signal);
    return signal == SIGINT ? "SIGINT" : "SIGTERM";
  }

 private:
  sigset_t signals_;
  sigset_t previous_;
};

struct Simulators {
  std::unique_ptr<ModbusTurntableServer> tcp;
  std::unique_ptr<ModbusTurntableServer> rtu;  // null: not served
  std::string camlibs;                         // the camlib folder, with DSLRs
  std::vector<std::unique_ptr<SimDslrServer>> dslrs;
  std::unique_ptr<SimGigECamera> gige;  // null: not served
};

Status StartSimulators(const SimServeOptions& o, const Scene& scene,
                       const std::shared_ptr<SimWorld>& world, Simulators* s) {
  const ModbusServerOptions modbus{ModbusRegisterMap{}, o.turntable_serial, o.slave_id};
  HR_ASSIGN_OR_RETURN(s->tcp,
                      ModbusTurntableServer::StartTcp(world, modbus, "127.0.0.1", o.modbus_port));
  if (o.rtu) {
    HR_ASSIGN_OR_RETURN(s->rtu, ModbusTurntableServer::StartRtu(world, modbus));
  }
  if (o.dslr) {  // one per scene camera, rendering that camera's view
    HR_ASSIGN_OR_RETURN(s->camlibs, SimDslrCamlibFolder());
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
      SimDslrOptions options;
      options.serial = scene.cameras[i].serial;
      options.scene_camera = static_cast<int>(i);
      HR_ASSIGN_OR_RETURN(auto server, SimDslrServer::Start(world, options));
      s->dslrs.push_back(std::move(server));
    }
  }
  // The GigE fake takes 127.0.0.1:3956, so only one camera: the scene's last.
  if (o.gige && !scene.cameras.empty()) {
    const int index = static_cast<int>(scene.cameras.size()) - 1;
    HR_ASSIGN_OR_RETURN(
        s->gige, SimGigECamera::Start(world, {scene.cameras.back().serial, index, "", true}));
  }
  return Status::Ok();
}

// How an outside tool reaches each simulator.
std::string DescribeEndpoints(const SimServeOptions& o, const Simulators& s) {
  std::string text =
      StringPrintf("simulated turntable controller %s (register map: etc/rig-example.yaml)\n",
                   o.turntable_serial.c_str());
  text += StringPrintf(
      "  %s\n    try: mbpoll -m tcp -p %d -a %d -0 -1 -t 4:int -B -r 10 127.0.0.1   (position, "
      "counts)\n",
      s.tcp->Describe().c_str(), s.tcp->port(), o.slave_id);
  if (s.rtu) {
    text += StringPrintf(
        "  %s\n    try: mbpoll -m rtu -b 115200 -P none -a %d -0 -1 -t 4 -r 1 %s   (status bits)\n",
        s.rtu->Describe().c_str(), o.slave_id, s.rtu->device_path().c_str());
  }
  if (!s.dslrs.empty()) {
    text += StringPrintf("simulated DSLRs (libgphoto2 camlib in %s)\n  export CAMLIBS=%s\n",
                         s.camlibs.c_str(), s.camlibs.c_str());
  }
  for (const auto& d : s.dslrs) {
    text += StringPrintf(
        "  %s\n    try: gphoto2 --camera '%s' --port %s --capture-image-and-download\n",
        d->Describe().c_str(), sim_dslr::kModel, d->port().c_str());
  }
  if (s.gige) {
    text += StringPrintf(
        "simulated GigE Vision camera (Aravis' fake, rendering the view)\n  %s\n    try: "
        "arv-tool-0.8 -a %s control DeviceSerialNumber Width Height PixelFormat\n",
        s.gige->Describe().c_str(), s.gige->address().c_str());
  }
  return text + "Ctrl-C stops.\n";
}

// Stops every simulator and reports what each served.
void StopSimulators(Simulators& s, SimServeSummary* summary) {
  s.tcp->Stop();
  if (s.rtu) s.rtu->Stop();
  if (s.gige) {
    summary->gige =
        SimServeSummary::GigE{s.gige->serial(), s.gige->address(), s.gige->frames_rendered()};
    s.gige.reset();
  }
  for (const auto& d : s.dslrs) {
    d->Stop();
    summary->dslr.push_back({d->serial(), d->port(), d->shots()});
  }
  for (const ModbusTurntableServer* server : {s.tcp.get(), s.rtu.get()}) {
    if (server != nullptr)
      summary->modbus.push_back({server->Describe(), server->requests_served()});
  }
}

}  // namespace

Status SimServeOptions::Check() const {
  if (scene_file.empty()) return InvalidArgument("sim serve: scene_file is required");
  if (modbus_port < 0 || modbus_port > 65535) {
    return InvalidArgument("sim serve: modbus_port must be 0 (a free port) to 65535, got " +
                           std::to_string(modbus_port));
  }
  if (slave_id < 1 || slave_id > 247) {
    return InvalidArgument("sim serve: slave_id must be a Modbus unit id 1-247, got " +
                           std::to_string(slave_id));
  }
  if (!(time_scale > 0) || !std::isfinite(time_scale)) {
    return InvalidArgument("sim serve: time_scale must be a positive number");
  }
  return Status::Ok();
}

nlohmann::json SimServeSummary::ToJson() const {
  nlohmann::json servers = nlohmann::json::array();
  for (const Modbus& s : modbus)
    servers.push_back({{"endpoint", s.endpoint}, {"requests_served", s.requests_served}});
  nlohmann::json cameras = nlohmann::json::array();
  for (const Dslr& d : dslr)
    cameras.push_back({{"serial", d.serial}, {"port", d.port}, {"shots", d.shots}});
  nlohmann::json gige_json = nullptr;
  if (gige)
    gige_json = {{"serial", gige->serial}, {"address", gige->address}, {"frames", gige->frames}};
  return {{"stopped_by", stopped_by}, {"modbus", servers}, {"dslr", cameras}, {"gige", gige_json}};
}

std::string SimServeSummary::BriefReport() const {
  std::string text = "stopped (" + stopped_by + ")\n";
  for (const Modbus& s : modbus)
    text += StringPrintf("  %s: %ld requests served\n", s.endpoint.c_str(), s.requests_served);
  if (gige) {
    text += StringPrintf("  simulated GigE Vision camera %s at %s: %d frames\n",
                         gige->serial.c_str(), gige->address.c_str(), gige->frames);
  }
  for (const Dslr& d : dslr)
    text += StringPrintf("  simulated DSLR %s at %s: %d shots\n", d.serial.c_str(), d.port.c_str(),
                         d.shots);
  return text;
}

Result<SimServeSummary> ServeSimulatedDevices(const SimServeOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  HR_ASSIGN_OR_RETURN(const Scene scene, LoadScene(options.scene_file));
  SimWorldOptions world_options;
  world_options.time_scale = options.time_scale;
  HR_ASSIGN_OR_RETURN(const std::shared_ptr<SimWorld> world, CreateSimWorld(scene, world_options));
  const StopSignalsBlocked stop_signals;  // before the simulators' threads start
  Simulators simulators;
  HR_RETURN_IF_ERROR(StartSimulators(options, scene, world, &simulators));
  if (options.on_serving) options.on_serving(DescribeEndpoints(options, simulators));
  SimServeSummary summary;
  summary.stopped_by = stop_signals.Wait();
  StopSimulators(simulators, &summary);
  return summary;
}

}  // namespace hairrig
