// A camera: industrial (Aravis, V4L2), DSLR (gphoto2) or simulated.
//
// Capture is split so that several cameras can be triggered together and their
// downloads overlap the next turntable move:
//   Configure(settings) -> Arm() -> [SoftwareTrigger() | pulse on the trigger line]
//   -> WaitFrame(timeout), any number of times; Disarm() when done.
// WaitFrame returns frames in trigger order, each with the time of the trigger
// it answers; Timeout if none arrives in time (the device stays usable; the
// late frame comes out of a later WaitFrame with its own, earlier trigger
// time), Unavailable if the camera dropped off the bus. A camera that ignores
// a trigger without reporting it shifts the pairing of its later frames; the
// backends cannot tell that from a late frame.
//
// States (drivers/device.h; each call checks its row, then calls its Do hook):
//   call              allowed in   transition
//   Configure         ready        -
//   Arm               ready        -> busy on success
//   Disarm            any state    busy -> ready on success
//   SoftwareTrigger   busy         -
//   LineTriggerSent   any state    -
//   WaitFrame         busy         -
//   CapturePreview    ready        -
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/device.h"

namespace hairrig {

enum class PixelFormat { kMono8, kRgb8, kBgr8, kBayerRG8, kEncoded };
const char* PixelFormatName(PixelFormat format);
int BytesPerPixel(PixelFormat format);  // 0 for kEncoded

enum class TriggerSource { kSoftware, kLine };

struct CaptureSettings {
  double exposure_s = 0.01;
  double gain_db = 0.0;
  PixelFormat format = PixelFormat::kRgb8;
  TriggerSource trigger = TriggerSource::kSoftware;
  std::string trigger_line;  // name of the TriggerLine device when trigger == kLine
};

struct CameraCapabilities {
  int width_px = 0;
  int height_px = 0;
  std::vector<PixelFormat> formats;
  double min_exposure_s = 0;
  double max_exposure_s = 0;
  bool line_trigger = false;
  double readout_s = 0;   // sensor readout after exposure
  double download_s = 0;  // typical transfer time of one frame
};

struct Frame {
  std::string camera_serial;
  uint64_t sequence = 0;  // per camera, from 0 after Arm()
  int width_px = 0;
  int height_px = 0;
  PixelFormat format = PixelFormat::kRgb8;
  std::string encoding;  // for kEncoded: file extension of `data` ("jpg", "png")
  std::vector<uint8_t> data;
  double exposure_s = 0;
  double gain_db = 0;
  int64_t trigger_time_ns = 0;   // steady clock, when the exposure started
  int64_t received_time_ns = 0;  // steady clock, when the host had all bytes
  // Bytes a raw frame of this geometry must have; 0 for encoded frames.
  size_t ExpectedBytes() const;
};

class Camera : public Device {
 public:
  using Device::Device;
  virtual CameraCapabilities capabilities() const = 0;
  // OutOfRange names the setting outside the capabilities.
  Status Configure(const CaptureSettings& settings);
  Status Arm();
  Status Disarm();
  Status SoftwareTrigger();
  // The host is about to pulse this camera's trigger line (TriggerSource::kLine);
  // `sent_ns` on the SteadyNowNs clock. Frames are dated by these, in order, as
  // by software triggers, so that a frame arriving after its view timed out
  // carries its own trigger time, not a guess from its arrival. Called for
  // every armed camera on the line, whether or not the host waits for its
  // frame. Backends that see the pulse themselves (simulated, replayed) ignore it.
  void LineTriggerSent(int64_t sent_ns);
  Result<Frame> WaitFrame(std::chrono::milliseconds timeout);
  // One frame of the camera's live-view stream (a DSLR's preview, smaller than
  // its shots), taken without firing the shutter, storing a file or counting a
  // shot; ready state (not armed), with the exposure of the last Configure.
  // Unimplemented when the camera has no such stream: a live view then
  // triggers full frames (harmless for industrial cameras, which have no
  // mechanical shutter).
  Result<Frame> CapturePreview(std::chrono::milliseconds timeout);

 protected:
  // The backend's side of the calls above, called once the state allows the call.
  virtual Status DoConfigure(const CaptureSettings& settings) = 0;
  // Starts acquisition; Arm marks the device busy after it succeeds.
  virtual Status DoArm() = 0;
  // Stops acquisition; Disarm marks a busy device ready after it succeeds.
  virtual Status DoDisarm() = 0;
  virtual Status DoSoftwareTrigger() = 0;
  virtual void DoLineTriggerSent(int64_t sent_ns) = 0;
  virtual Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) = 0;
  // Unimplemented unless the backend has a live-view stream.
  virtual Result<Frame> DoCapturePreview(std::chrono::milliseconds timeout) {
    (void)timeout;
    return Unimplemented(Describe() + ": no live-view stream");
  }
};

}  // namespace hairrig
