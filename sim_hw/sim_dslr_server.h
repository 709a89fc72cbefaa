// A simulated DSLR, reached through libgphoto2: the camera side of the
// protocol in sim_hw/sim_dslr_protocol.h, served on `<folder>/camera.sock`.
// The project's camlib (sim_hw/gphoto2_camlib) connects to it when libgphoto2
// opens the port `disk:<folder>`, so the real `gphoto2` backend and the
// unmodified `gphoto2` command drive this camera.
//
// The camera renders the world (turntable angle and lights at the start of
// the exposure) through one scene camera and stores each shot as a JPEG on
// its "card" (in memory) until the client deletes it:
//   - CAPTURE shoots and replies with the file's path once it is written;
//   - TRIGGER shoots and returns at once; the file arrives as a FILE_ADDED event;
//   - a pulse on `trigger_line` (the world's trigger bus) shoots like TRIGGER.
// Timings: exposure (shutterspeed) + the scene's readout and download, times
// the world's time_scale, before a file is announced.
//
// Settings (gphoto2 names): iso (gain = 20 log10(iso / 100) dB), shutterspeed
// (the exposure), aperture (accepted and reported; the renderer has no depth
// of field), imageformat (JPEG quality), capturetarget; read-only
// serialnumber, cameramodel, manufacturer.
//
// Faults: the world's camera faults for `serial` (drop_frame, camera_gone,
// download_timeout; sim_hw/sim_faults.h) hit shots as they do the `sim`
// camera; InjectFault adds protocol faults for the next requests. While
// gone, the server drops every connection and refuses new ones.
#pragma once

#include <memory>
#include <string>

#include "core/status.h"

namespace hairrig {

class SimWorld;

struct SimDslrOptions {
  std::string serial;        // the camera's serial number (required)
  int scene_camera = 0;      // the scene camera whose view it renders
  std::string trigger_line;  // world trigger line that fires the shutter; "" for none
  std::string folder;  // the port folder; "" makes a fresh one under $TMPDIR (removed on Stop;
                       // stale ones of killed processes are removed first)
  int reply_timeout_ms = 30000;  // the camlib's limit on waiting for any reply (told in HELLO)

  // InvalidArgument naming the field: an empty serial, a negative
  // scene_camera, a reply_timeout_ms below 1.
  Status Check() const;
};

// The folder holding the simulated DSLR's camlib beside links to the system
// camlibs: $HAIRRIG_CAMLIBS, else the build's camlibs folder. NotFound when
// hairrig_sim_dslr.so is not there (build the hairrig_sim_dslr target).
Result<std::string> SimDslrCamlibFolder();
// Points libgphoto2 in this process at that folder (sets CAMLIBS) before it
// loads its drivers. InvalidArgument when CAMLIBS is already set to a folder
// without the simulated DSLR's camlib.
Status ExportSimDslrCamlibs();

// Removes the folders hairrig-dslr-* directly under `parent` that a killed
// process left behind: owned by this user, not symbolic links, naming in
// their owner.pid a process that no longer exists, with nothing listening on
// their socket. A folder without owner.pid (one being made, or made by an
// older build) is kept. Returns how many were removed.
int RemoveStaleSimDslrFolders(const std::string& parent);

class SimDslrServer {
 public:
  enum class Fault {
    kBusy,        // the next `count` requests answer ERR busy (camera busy, e.g. focusing)
    kNoReply,     // the next `count` requests get no reply (the client times out)
    kDisconnect,  // the next request closes the connection (a cable pulled mid-transfer)
    kClaimed,     // the next `count` connections are refused as claimed by another process
  };

  // Binds the socket and starts serving. InvalidArgument for bad options
  // (SimDslrOptions::Check) or a scene camera the scene lacks; IoError when
  // the folder or socket cannot be made.
  static Result<std::unique_ptr<SimDslrServer>> Start(std::shared_ptr<SimWorld> world,
                                                      SimDslrOptions options);
  ~SimDslrServer();
  SimDslrServer(const SimDslrServer&) = delete;
  SimDslrServer& operator=(const SimDslrServer&) = delete;

  const std::string& folder() const;
  std::string port() const { return "disk:" + folder(); }  // the gphoto2 port path
  const std::string& serial() const;
  std::string Describe() const;  // "simulated DSLR SIM-CAM-UPPER at disk:/tmp/..."

  void InjectFault(Fault fault, int count = 1);
  int shots() const;        // files written since Start
  int connections() const;  // connections accepted since Start
  // Stops serving; connected clients see the camera vanish. Safe to call twice.
  void Stop();

  class Impl;

 private:
  explicit SimDslrServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
