// The `gphoto2` camera backend: DSLRs and mirrorless cameras through
// libgphoto2 (USB PTP for real bodies; the project's simulated DSLR through
// its camlib, sim_hw/gphoto2_camlib).
//
// Config fields (devices.cameras[i]):
//   serial:   the body's serial number (required; checked on every Open)
//   port:     a libgphoto2 port ("usb:001,004", "disk:/path"); optional: by
//             default every auto-detected camera is opened until one reports
//             `serial`, so the body can move to another USB socket
//   model:    the libgphoto2 model name; needed only where detection cannot
//             name it (disk: ports)
//   settings: {name: value} written at Open, by gphoto2 config name
//             (iso, aperture, imageformat, capturetarget, ...); a name the body
//             lacks or a value outside its choices is refused with the choices
//   keep_on_camera: false (default) deletes each shot from the body after download
//   width_px, height_px: the image size, to check each download (optional)
//   readout_s, download_s: nominal timings for the capture's time budget
//             (defaults 0.2 and 1.0 s)
//   trigger_line: as for every camera (a wired remote on a GPIO line)
//
// Capture: SoftwareTrigger() fires the shutter (gp_camera_trigger_capture);
// WaitFrame() waits for the body's FILE_ADDED event, downloads the file and
// returns it as an encoded frame (the body's JPEG, untouched). With a line
// trigger the pulse fires the shutter and WaitFrame works the same way; the
// frame's trigger time is then estimated as arrival minus exposure, readout
// and download. Configure() maps exposure_s to the nearest `shutterspeed`
// choice and gain_db to the nearest `iso` choice (ISO 100 x 10^(gain_db/20));
// the requested pixel format does not apply (a body writes its imageformat).
//
// Failures, each naming the camera and what to do:
//   claimed by another process (GP_ERROR_IO_USB_CLAIM) -> Unavailable
//   busy (GP_ERROR_CAMERA_BUSY): retried 3 times, 0.2 s apart, then DeviceFault
//   no answer (GP_ERROR_TIMEOUT) -> Timeout (the camera stays usable)
//   gone (I/O error, not found) -> Unavailable and faulted; Open() again
//   reconnects, finding the body by serial wherever it re-enumerated.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/camera.h"
#include "drivers/camera_support.h"
#include "drivers/registry.h"

namespace hairrig {

struct Gphoto2CameraOptions {
  std::string port;
  std::string model;
  std::vector<std::pair<std::string, std::string>> settings;  // in config order
  bool keep_on_camera = false;
  CameraNominal nominal;  // width_px, height_px, readout_s (0.2), download_s (1.0)
  int busy_attempts = 3;
  double busy_backoff_s = 0.2;

  // InvalidArgument naming the field for a value out of range (the hook's
  // rewrites included): a disk: port without its model, busy_attempts below
  // 1, a negative or non-finite busy_backoff_s, the nominal timings.
  Status Check() const;
};

Result<Gphoto2CameraOptions> ParseGphoto2CameraOptions(const ConfigNode& device);

std::unique_ptr<Camera> MakeGphoto2Camera(const DeviceInfo& info, Gphoto2CameraOptions options);

// A camera libgphoto2 auto-detects, with the serial it reports once opened.
struct Gphoto2Detected {
  std::string model;
  std::string port;
  std::string serial;  // "" when the camera could not be opened
  std::string error;   // why it could not be opened
};
// Auto-detects the connected cameras and opens each to read its serial
// (cameras already open in this process are reported with an error).
Result<std::vector<Gphoto2Detected>> DetectGphoto2Cameras();

// Runs before each device is built; may rewrite the options (the simulated
// rig points `port` at a simulated body it starts).
using Gphoto2OptionsHook = std::function<Status(const DeviceConfig&, Gphoto2CameraOptions*)>;
void RegisterGphoto2Backend(DeviceRegistry* registry, Gphoto2OptionsHook hook = nullptr);

}  // namespace hairrig
