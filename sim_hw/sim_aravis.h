// Aravis' own fake camera, fed with the simulated world's rendered views, as
// the peer of the `aravis` backend (drivers/aravis_camera.h). Two ways in:
//   - in-process: OpenSimAravisCamera makes an ArvFakeDevice (Aravis' fake
//     GenICam device, with its register map and stream) carrying the scene
//     camera's serial, and opens it as an ArvCamera;
//   - GigE Vision on 127.0.0.1: SimGigECamera runs Aravis' GigE fake camera
//     (GVCP on port 3956, so one per machine at a time); the backend opens it
//     by address like any GigE camera, over real UDP packets. Its sockets are
//     guarded (sim_hw/gvcp_guard.h): a kernel filter drops control packets
//     that would crash Aravis' fake, and its discovery socket (bound to
//     255.255.255.255) is confined to the loopback interface. It refuses to
//     start beside another server on that port (another fake would take
//     part of the client's packets and answer with its own images).
// Either way each frame is rendered when the fake camera produces it (a
// software trigger, or a pulse on the world's trigger line when the camera is
// in Line0 trigger mode), at the world's turntable angle and lights, and
// converted to the camera's pixel format (Mono8, RGB8, BayerRG8 as an RGGB
// mosaic; Mono16 scaled x257). Aravis' fake paces triggers at 25 Hz by
// default; the feed raises that to 1 kHz. A frame is filled in the fake's own
// thread, so a busy machine makes it late, never different. A frame the feed
// does not fill with the view (the render fails, the registers ask for more
// than the buffer holds, the acquisition stops while the frame waits for its
// trigger) is never served as an image: its buffer carries frame id 0, which
// GigE Vision reserves, and the GigE fake sends none of its packets (the
// client sees no frame, then a gap in the frame ids); the `aravis` backend
// reports both.
//
// Triggers: the in-process fake streams continuously whatever its trigger
// mode, so the feed holds each frame until its software trigger or line
// pulse arrives. Aravis' fake has no electrical input: a pulse on the world's
// trigger line stands for Line0 (on the GigE fake, which only honours
// software triggers, TriggerSource reads Software until the frame is made).
// The frame shows the world as it was at the pulse.
#pragma once

#include <memory>
#include <string>

#include "core/status.h"

typedef struct _ArvCamera ArvCamera;
typedef struct _ArvFakeCamera ArvFakeCamera;
typedef struct _ArvGvFakeCamera ArvGvFakeCamera;

namespace hairrig {

class SimWorld;

struct SimAravisOptions {
  std::string serial;        // the camera's serial (DeviceSerialNumber)
  int scene_camera = 0;      // the scene camera whose view it renders
  std::string trigger_line;  // world trigger line wired to Line0; "" for none
  bool render = true;  // false: Aravis' own test pattern (to time the transport alone; GigE only)

  // InvalidArgument naming the field: an empty serial, a negative scene_camera.
  Status Check() const;
};

// Renders the world into one fake camera's buffers. Keep it alive as long
// as the fake camera streams.
class SimAravisFeed {
 public:
  SimAravisFeed(std::shared_ptr<SimWorld> world, SimAravisOptions options);
  ~SimAravisFeed();
  SimAravisFeed(const SimAravisFeed&) = delete;
  SimAravisFeed& operator=(const SimAravisFeed&) = delete;

  // Routes `fake`'s fill pattern through this feed (one fake per feed).
  // `gige`: the GigE fake serving `fake`, which produces frames on software
  // triggers only; null for the in-process fake, which streams continuously
  // (the feed holds each frame until its trigger).
  void Attach(ArvFakeCamera* fake, ArvGvFakeCamera* gige = nullptr);
  // Whether a GigE fake's frames show the view or Aravis' own test pattern
  // (SimAravisOptions::render); an attached feed attaches again to its fake.
  // The in-process fake's frames show the view either way.
  void SetRender(bool render);
  // Frames made for a trigger, those withheld for want of the view included.
  int frames_rendered() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// An in-process Aravis fake camera with `feed`'s serial, opened. The caller
// owns the returned reference (g_object_unref); `feed` must outlive it.
// InvalidArgument for bad options (SimAravisOptions::Check).
Result<ArvCamera*> OpenSimAravisCamera(SimAravisFeed& feed, const SimAravisOptions& options);

// Aravis' GigE Vision fake camera on 127.0.0.1, fed by the world.
class SimGigECamera {
 public:
  // Unavailable when Aravis cannot serve on 127.0.0.1, or when another socket
  // already takes packets for 127.0.0.1:3956 (another GigE fake: Aravis lets
  // both bind it, and the client would get part of its answers and images
  // from the other). Run one at a time (tests hold the ctest resource lock
  // gige_fake_port). InvalidArgument for bad options (SimAravisOptions::Check).
  static Result<std::unique_ptr<SimGigECamera>> Start(std::shared_ptr<SimWorld> world,
                                                      SimAravisOptions options);
  ~SimGigECamera();
  const std::string& address() const;  // "127.0.0.1"
  const std::string& serial() const;
  int frames_rendered() const;
  // Its frames show the view (true) or Aravis' own test pattern, from the
  // next frame on (SimAravisOptions::render at Start).
  void SetRender(bool render);
  std::string Describe() const;  // "simulated GigE Vision camera SIM-CAM-LOWER at 127.0.0.1"

  class Impl;

 private:
  explicit SimGigECamera(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairrig
