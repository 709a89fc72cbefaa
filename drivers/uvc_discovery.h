// Finds V4L2 video-capture devices (/dev/video*): for `hairrig devices
// --discover` and for the v4l2 backend's search by serial.
#pragma once

#include <string>
#include <vector>

namespace hairrig {

struct V4l2Detected {
  std::string path;      // "/dev/video0"
  std::string card;      // VIDIOC_QUERYCAP card: "HD Pro Webcam C920"
  std::string driver;    // "uvcvideo"
  std::string bus_info;  // "usb-0000:00:14.0-2"
  std::string serial;    // the USB device's serial (sysfs); "" when it has none
  std::string error;     // why the node could not be queried (permissions...)
};

class V4l2Io;

// Video-capture nodes only (a UVC camera's metadata node is left out).
std::vector<V4l2Detected> DetectV4l2Cameras(V4l2Io& io);
std::vector<V4l2Detected> DetectV4l2Cameras();  // through the system calls

}  // namespace hairrig
