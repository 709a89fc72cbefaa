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
//              by WaitFrame wait there; a frame that arrives while all are
//              full is dropped by the stream (its misses count as underruns)
//   packet_size: GigE packet size in bytes (default: negotiated)
//   trigger_line: as for every camera; the camera is set to TriggerSource
//              Line0 (or `trigger_source`) with TriggerMode On
//   trigger_source: the GenICam line name for the trigger (default Line0)
//
// Pixel formats: Mono8, RGB8 and BayerRG8 are delivered as they come; a
// BayerRG8 camera asked for rgb8/bgr8 is debayered with OpenCV. Mono16 is not
// offered (hairrig's frames are 8-bit).
//
// Capture: Arm() fills the buffer pool, then starts acquisition in trigger
// mode; SoftwareTrigger() sends TriggerSoftware; WaitFrame() pops the next
// complete buffer. Every buffer the stream delivers answers one trigger, and
// its frame id is checked (AravisFrameIds, below), whether it brings an image
// or not. Failures, each CorruptData:
//   - a buffer that arrives incomplete (missing packets);
//   - a frame with frame id 0 from a GigE Vision camera (or Aravis' fake),
//     which reserves that id: the camera sent no image for that trigger;
//   - a gap in the frame ids (GigE and USB3 Vision cameras number every frame
//     they send): frames the stream dropped for want of a free buffer or lost
//     on the network. The frames after it cannot be paired with their
//     triggers: every WaitFrame returns that same CorruptData (it says to
//     re-arm the camera) until the camera is armed again.
// After the first two the camera stays usable; after a gap it must be armed
// again (Disarm, Arm).
// Timeout when no buffer arrives in time (the message says how often the
// stream found no free buffer since Arm); Unavailable (and faulted) when the
// camera is gone. Statistics (completed, failed, underruns; for GigE resent
// and missing packets) are read with AravisCameraStreamStats.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
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

  // InvalidArgument naming the config field for a value out of the range
  // ParseAravisCameraOptions accepts (the hook's rewrites included).
  Status Check() const;
};

Result<AravisCameraOptions> ParseAravisCameraOptions(const ConfigNode& device);

std::unique_ptr<Camera> MakeAravisCamera(const DeviceInfo& info, AravisCameraOptions options);

struct AravisStreamStats {
  uint64_t completed = 0;
  uint64_t failures = 0;         // buffers that arrived incomplete or late
  uint64_t underruns = 0;        // times the stream found no free buffer for arriving data
  uint64_t resent_packets = 0;   // GigE only
  uint64_t missing_packets = 0;  // GigE only
};
// The statistics of the camera's current (or last) stream; zeros for a
// camera of another backend.
AravisStreamStats AravisCameraStreamStats(const Camera& camera);

// The frame-id check the backend runs on every buffer its stream delivers
// (declared here for tests). GigE Vision and USB3 Vision cameras, and Aravis'
// fake, number the frames they send one by one; GigE Vision's 16-bit ids run
// 1..65535 and wrap to 1 (0 is reserved). A buffer that brings no image
// counts as well: by its id, or, when it carries id 0, as the frame after the
// last one (it answered a trigger). A gap means frames dropped by the stream
// or lost on the network, and the frames after it cannot be paired with their
// triggers.
class AravisFrameIds {
 public:
  // `skips_zero`: 16-bit ids with 0 reserved (GigE Vision, Aravis' fake);
  // `counts_frames`: ids go up by one per frame (those and USB3 Vision);
  // without it no id is checked.
  explicit AravisFrameIds(bool skips_zero = false, bool counts_frames = false)
      : skips_zero_(skips_zero), counts_frames_(counts_frames) {}
  // A new stream (Arm): the next id starts the count, and a gap is forgotten.
  void Reset();
  // The id of the next buffer delivered (0: none). Ok when it follows the
  // last one; at a gap, or an id that does not go forward, CorruptData
  // "`camera`: frame id B after A means N frame(s) lost ...`note`; ... re-arm
  // the camera", and that same status for every buffer after it until Reset.
  Status Next(uint64_t id, const std::string& camera, const std::string& note = "");
  // The gap found since Reset (Ok: none).
  const Status& gap() const { return gap_; }

 private:
  bool skips_zero_ = false;
  bool counts_frames_ = false;
  std::optional<uint64_t> last_;  // the last buffer's id that was not 0, since Reset
  uint64_t unnumbered_ = 0;       // buffers with id 0 since that one
  Status gap_;
};

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
