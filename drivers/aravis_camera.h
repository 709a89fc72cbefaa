// The `aravis` camera backend: GigE Vision and USB3 Vision cameras through
// Aravis (GenICam features PixelFormat, Width/Height, ExposureTime, Gain,
// TriggerMode/TriggerSource).
//
// Config fields (devices.cameras[i]):
//   serial:    the camera's serial number (required; checked on every Open)
//   address:   optional: open by IP address ("192.168.10.31") or Aravis device
//              id instead of searching every interface for `serial`
//   width_px, height_px: the region of interest, from the sensor's top left
//              (default: the whole sensor)
//   buffers:   stream buffers in the pool (default 8): frames not yet taken
//              by WaitFrame wait there; when all are full, the camera's
//              frames are dropped and counted as underruns
//   packet_size: GigE packet size in bytes (default: negotiated)
//   trigger_line: as for every camera; the camera is set to TriggerSource
//              Line0 (or `trigger_source`) with TriggerMode On
//   trigger_source: the GenICam line name for the trigger (default Line0)
//
// Pixel formats: Mono8, RGB8 and BayerRG8 are delivered as they come; a
// BayerRG8 camera asked for rgb8/bgr8 is debayered with OpenCV. Mono16 is not
// offered (hairrig's frames are 8-bit).
//
// Capture: Arm() starts acquisition in trigger mode with the buffer pool;
// SoftwareTrigger() sends TriggerSoftware; WaitFrame() pops the next complete
// buffer. A buffer that arrives incomplete (missing packets) is reported as
// CorruptData and counted; the camera stays usable. Timeout when no buffer
// arrives in time; Unavailable (and faulted) when the camera is gone.
// Statistics (completed, failed, underruns; for GigE resent and missing
// packets) are read with AravisCameraStreamStats.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "drivers/camera.h"
#include "drivers/camera_support.h"
#include "drivers/registry.h"

typedef struct _ArvCamera ArvCamera;

namespace hairrig {

struct AravisCameraOptions {
  std::string address;
  // width_px, height_px (0: the sensor's), readout_s (0.01), download_s (0.05)
  CameraNominal nominal{0, 0, 0.01, 0.05, 1.0};
  int buffers = 8;
  int packet_size = 0;  // 0: negotiated
  std::string trigger_source = "Line0";
  // Opens the camera instead of the search by address or serial (a hook
  // supplies it: Aravis' in-process fake camera, for one); the serial is still
  // checked. The device takes the returned reference.
  std::function<Result<ArvCamera*>()> connect;
  std::string connect_name;  // how messages name the camera `connect` opens
};

Result<AravisCameraOptions> ParseAravisCameraOptions(const ConfigNode& device);

std::unique_ptr<Camera> MakeAravisCamera(const DeviceInfo& info, AravisCameraOptions options);

struct AravisStreamStats {
  uint64_t completed = 0;
  uint64_t failures = 0;         // buffers that arrived incomplete or late
  uint64_t underruns = 0;        // frames dropped for want of a free buffer
  uint64_t resent_packets = 0;   // GigE only
  uint64_t missing_packets = 0;  // GigE only
};
// The statistics of the camera's current (or last) stream; zeros for a
// camera of another backend.
AravisStreamStats AravisCameraStreamStats(const Camera& camera);

// A camera Aravis finds on its interfaces.
struct AravisDetected {
  std::string id;  // Aravis device id
  std::string vendor;
  std::string model;
  std::string serial;
  std::string address;   // IP address (GigE) or bus path
  std::string protocol;  // "GigEVision", "USB3Vision", "Fake"
};
std::vector<AravisDetected> DetectAravisCameras();

using AravisOptionsHook = std::function<Status(const DeviceConfig&, AravisCameraOptions*)>;
void RegisterAravisBackend(DeviceRegistry* registry, AravisOptionsHook hook = nullptr);

}  // namespace hairrig
