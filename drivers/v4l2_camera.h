// The `v4l2` camera backend: UVC (USB video class) cameras through V4L2,
// with mmap streaming. Every system call goes through drivers/v4l2_io.h, so
// the tests run this code against a fake device (sim_hw/sim_v4l2.h).
//
// Config fields (devices.cameras[i]):
//   serial:   the USB serial of the camera (required): the node is found by it
//   device:   optional: a /dev/video* path, still checked against the serial
//   width_px, height_px: the frame size to negotiate (default 1280 x 720); the
//             driver may answer another size, which is refused with the sizes
//             it offers
//   format:   mjpeg | yuyv | auto (default: mjpeg when offered, else yuyv)
//   buffers:  mmap buffers (default 4)
//   readout_s, download_s: nominal timings for the capture's time budget
//
// UVC cameras stream continuously and have no trigger input: a software
// trigger takes the first frame exposed after it (frames the camera queued
// before the trigger are returned to the driver unread); a line trigger is
// refused. Exposure is set as V4L2_CID_EXPOSURE_ABSOLUTE (100 us units) with
// auto exposure off; gain as V4L2_CID_GAIN, in the camera's own units (UVC
// has no dB scale), when the camera has the controls (otherwise OutOfRange
// for a non-default request). Frames are decoded (MJPEG with OpenCV, YUYV
// converted) to the requested rgb8, bgr8 or mono8.
//
// Failures: a node that vanished or answers EIO/ENODEV faults the camera
// (Unavailable; Open finds it again by serial); a corrupt MJPEG frame is
// CorruptData and the camera stays usable.
#pragma once

#include <memory>
#include <string>

#include "drivers/camera.h"
#include "drivers/camera_support.h"
#include "drivers/registry.h"
#include "drivers/v4l2_io.h"

namespace hairrig {

enum class V4l2Wire { kAuto, kMjpeg, kYuyv };

struct V4l2CameraOptions {
  std::string device;
  V4l2Wire wire = V4l2Wire::kAuto;
  int buffers = 4;
  CameraNominal nominal{1280, 720, 0.0, 0.05, 1.0};
  std::shared_ptr<V4l2Io> io;  // null: the system calls

  // InvalidArgument naming the config field for a value out of the range
  // ParseV4l2CameraOptions accepts (the hook's rewrites included).
  Status Check() const;
};

Result<V4l2CameraOptions> ParseV4l2CameraOptions(const ConfigNode& device);
std::unique_ptr<Camera> MakeV4l2Camera(const DeviceInfo& info, V4l2CameraOptions options);

using V4l2OptionsHook = std::function<Status(const DeviceConfig&, V4l2CameraOptions*)>;
void RegisterV4l2Backend(DeviceRegistry* registry, V4l2OptionsHook hook = nullptr);

}  // namespace hairrig
