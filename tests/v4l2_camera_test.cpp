// The `v4l2` camera backend against a fake UVC camera behind its system-call
// layer (open/ioctl/mmap/poll), showing the rendered world.
#include "drivers/v4l2_camera.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_v4l2.h"
#include "tests/support/camera_checks.h"
#include "tests/support/sim_world.h"

namespace hairrig {
namespace {

using hairrig_test::kFrameWait;
using hairrig_test::Psnr;
using hairrig_test::ShootOnce;

using std::chrono::milliseconds;
constexpr char kSerial[] = "SIM-CAM-UPPER";

struct Bench {
  std::shared_ptr<SimWorld> world;
  std::shared_ptr<SimV4l2Device> fake;
  std::unique_ptr<Camera> camera;
};

Bench Start(V4l2Wire wire = V4l2Wire::kAuto, const std::string& device_serial = kSerial,
            int width = 1200) {
  Bench b;
  b.world = hairrig_test::MakeSimWorld({}, /*lights_on=*/true);
  b.fake = std::make_shared<SimV4l2Device>(b.world, SimV4l2Options{kSerial, 0, "/dev/video0", 30});
  V4l2CameraOptions o;
  o.io = b.fake;
  o.wire = wire;
  o.nominal = {width, 1600, 0.0, 0.05, 0.01};
  b.camera = MakeV4l2Camera({DeviceKind::kCamera, "uvc", "v4l2", device_serial, "test"}, o);
  return b;
}

cv::Mat Reference(const Bench& b) {
  return RenderWorldExposure(*b.world, 0, ExposeWorldNow(*b.world), 0.02, 0, 0).value();
}

TEST(V4l2Camera, MjpegFramesAreTheRenderedView) {
  Bench b = Start();
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->HealthCheck().ok());
  auto frame = ShootOnce(*b.camera, PixelFormat::kRgb8);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  ASSERT_EQ(frame->data.size(), frame->ExpectedBytes());
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(1600, 1200, CV_8UC3, frame->data.data()), bgr, cv::COLOR_RGB2BGR);
  EXPECT_GT(Psnr(bgr, Reference(b)), 33.0);  // JPEG quality 90
  EXPECT_GT(cv::mean(bgr)[1], 20.0);
}

TEST(V4l2Camera, YuyvFramesAreConvertedToGrey) {
  Bench b = Start(V4l2Wire::kYuyv);
  ASSERT_TRUE(b.camera->Open().ok());
  auto frame = ShootOnce(*b.camera, PixelFormat::kMono8);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  cv::Mat grey;
  cv::cvtColor(Reference(b), grey, cv::COLOR_BGR2GRAY);
  EXPECT_GT(Psnr(cv::Mat(1600, 1200, CV_8UC1, frame->data.data()), grey), 35.0);
}

TEST(V4l2Camera, ConfigureSetsManualExposureInHundredMicroseconds) {
  Bench b = Start();
  ASSERT_TRUE(b.camera->Open().ok());
  CaptureSettings s;
  s.exposure_s = 0.0125;
  ASSERT_TRUE(b.camera->Configure(s).ok());
  const int fd = b.fake->Open("/dev/video0", O_RDWR);
  v4l2_control exposure{V4L2_CID_EXPOSURE_ABSOLUTE, 0};
  v4l2_control mode{V4L2_CID_EXPOSURE_AUTO, 0};
  ASSERT_EQ(b.fake->Ioctl(fd, VIDIOC_G_CTRL, &exposure), 0);
  ASSERT_EQ(b.fake->Ioctl(fd, VIDIOC_G_CTRL, &mode), 0);
  EXPECT_EQ(exposure.value, 125);
  EXPECT_EQ(mode.value, V4L2_EXPOSURE_MANUAL);
  b.fake->Close(fd);
  s.trigger = TriggerSource::kLine;
  s.trigger_line = "trig0";
  const Status line = b.camera->Configure(s);
  EXPECT_EQ(line.code(), StatusCode::kOutOfRange);
  EXPECT_NE(line.message().find("no trigger input"), std::string::npos) << line.message();
}

// The stream runs before the trigger; the frame returned is one exposed after it.
TEST(V4l2Camera, FramesQueuedBeforeTheTriggerAreSkipped) {
  Bench b = Start();
  ASSERT_TRUE(b.camera->Open().ok());
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  ASSERT_TRUE(b.camera->Configure(s).ok());
  for (const char* light : {"top", "bottom"})
    ASSERT_TRUE(SetWorldLightLevel(*b.world, light, 0.0).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  ASSERT_TRUE(b.fake->WaitUntilQueuedBuffersFilled(kFrameWait));  // every buffer holds a dark frame
  for (const char* light : {"top", "bottom"})
    ASSERT_TRUE(SetWorldLightLevel(*b.world, light, 1.0).ok());
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  auto frame = b.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_GT(cv::mean(cv::Mat(1600, 1200, CV_8UC1, frame->data.data()))[0], 20.0);  // lit
  EXPECT_GT(b.fake->frames_delivered(), 1);  // stale frames came first and were requeued
  EXPECT_EQ(b.camera->WaitFrame(milliseconds(50)).status().code(), StatusCode::kTimeout);
}

TEST(V4l2Camera, AnotherSerialOrSizeIsRefused) {
  Bench wrong = Start(V4l2Wire::kAuto, "SIM-CAM-LOWER");
  Status s = wrong.camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("has serial 'SIM-CAM-UPPER'"), std::string::npos) << s.message();

  Bench size = Start(V4l2Wire::kAuto, kSerial, 1920);
  s = size.camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange) << s.ToString();
  EXPECT_NE(s.message().find("offers 1200x1600 MJPG"), std::string::npos) << s.message();
}

TEST(V4l2Camera, AnUnpluggedCameraFaultsAndReopensWhenBack) {
  Bench b = Start();
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->Configure({}).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  b.fake->Unplug();
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  const Status s = b.camera->WaitFrame(kFrameWait).status();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("dropped off the bus"), std::string::npos) << s.message();
  EXPECT_EQ(b.camera->state(), DeviceState::kFaulted);
  EXPECT_EQ(b.camera->Open().code(), StatusCode::kUnavailable);  // still unplugged
  b.fake->Replug();
  ASSERT_TRUE(b.camera->Open().ok());
  EXPECT_TRUE(ShootOnce(*b.camera, PixelFormat::kRgb8).ok());
}

TEST(V4l2Camera, ACorruptFrameIsReportedAndTheNextOneIsFine) {
  Bench b = Start();
  ASSERT_TRUE(b.camera->Open().ok());
  ASSERT_TRUE(b.camera->Configure({}).ok());
  ASSERT_TRUE(b.camera->Arm().ok());
  // The buffers hold good frames taken before the trigger.
  ASSERT_TRUE(b.fake->WaitUntilQueuedBuffersFilled(kFrameWait));
  b.fake->CorruptNextFrames(1);
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  auto bad = b.camera->WaitFrame(kFrameWait);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kCorruptData) << bad.status().ToString();
  EXPECT_EQ(b.camera->state(), DeviceState::kBusy);
  ASSERT_TRUE(b.camera->SoftwareTrigger().ok());
  EXPECT_TRUE(b.camera->WaitFrame(kFrameWait).ok());
}

TEST(V4l2Camera, ConfigErrorsNameTheField) {
  auto root =
      ConfigNode::LoadString("{name: c, backend: v4l2, serial: X, format: h264}", "rig.yaml");
  auto parsed = ParseV4l2CameraOptions(*root);
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.status().message().find("format"), std::string::npos)
      << parsed.status().message();
}

}  // namespace
}  // namespace hairrig
