// The `aravis` camera backend against Aravis' own fake camera fed with the
// rendered world: in-process (ArvFakeDevice) and as a GigE Vision camera on
// 127.0.0.1, over real GVCP/GVSP packets.
#include "drivers/aravis_camera.h"

#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/clock.h"
#include "core/config.h"
#include "sim_hw/gvcp_guard.h"
#include "sim_hw/scene.h"
#include "sim_hw/sim_aravis.h"
#include "sim_hw/sim_devices.h"
#include "tests/support/camera_checks.h"
#include "tests/support/gvcp_packets.h"
#include "tests/support/sim_world.h"

namespace hairrig {
namespace {

using hairrig_test::ArmOnLine;
using hairrig_test::kFrameWait;
using hairrig_test::Psnr;
using hairrig_test::ShootOnce;

using std::chrono::milliseconds;
constexpr char kSerial[] = "SIM-CAM-LOWER";
constexpr int kSceneCamera = 1;

struct World {
  std::shared_ptr<SimWorld> world;  // with its panels on, so that the views are lit
};

World MakeWorld() { return {hairrig_test::MakeSimWorld({}, /*lights_on=*/true)}; }

AravisCameraOptions BaseOptions() {
  AravisCameraOptions o;
  o.nominal.width_px = 1200;
  o.nominal.height_px = 1600;
  o.nominal.time_scale = 0.01;
  return o;
}

struct InProcess {
  World w;
  std::unique_ptr<SimAravisFeed> feed;
  std::unique_ptr<Camera> camera;
};

// The backend on Aravis' in-process fake with serial `fake_serial`, configured for `device_serial`.
InProcess StartInProcess(const std::string& trigger_line = "",
                         const std::string& fake_serial = kSerial,
                         const std::string& device_serial = kSerial) {
  InProcess p;
  p.w = MakeWorld();
  const SimAravisOptions feed_options{fake_serial, kSceneCamera, trigger_line};
  p.feed = std::make_unique<SimAravisFeed>(p.w.world, feed_options);
  AravisCameraOptions o = BaseOptions();
  SimAravisFeed* feed = p.feed.get();
  o.connect = [feed, feed_options]() { return OpenSimAravisCamera(*feed, feed_options); };
  p.camera = MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", device_serial, "test"}, o);
  return p;
}

cv::Mat Reference(const World& w) {
  return RenderWorldExposure(*w.world, kSceneCamera, ExposeWorldNow(*w.world), 0.02, 0, 0).value();
}

TEST(AravisCamera, DeliversTheRenderedViewInEachPixelFormat) {
  InProcess p = StartInProcess();
  ASSERT_TRUE(p.camera->Open().ok());
  ASSERT_TRUE(p.camera->HealthCheck().ok());
  EXPECT_EQ(p.camera->capabilities().width_px, 1200);
  const cv::Mat reference = Reference(p.w);

  auto rgb = ShootOnce(*p.camera, PixelFormat::kRgb8);
  ASSERT_TRUE(rgb.ok()) << rgb.status().ToString();
  ASSERT_EQ(rgb->data.size(), rgb->ExpectedBytes());
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(1600, 1200, CV_8UC3, rgb->data.data()), bgr, cv::COLOR_RGB2BGR);
  EXPECT_GT(Psnr(bgr, reference), 40.0);
  EXPECT_GT(cv::mean(bgr)[1], 20.0);  // lit, not black

  auto mono = ShootOnce(*p.camera, PixelFormat::kMono8);
  ASSERT_TRUE(mono.ok()) << mono.status().ToString();
  cv::Mat grey;
  cv::cvtColor(reference, grey, cv::COLOR_BGR2GRAY);
  EXPECT_GT(Psnr(cv::Mat(1600, 1200, CV_8UC1, mono->data.data()), grey), 40.0);

  auto bayer = ShootOnce(*p.camera, PixelFormat::kBayerRG8);
  ASSERT_TRUE(bayer.ok()) << bayer.status().ToString();
  EXPECT_GT(Psnr(cv::Mat(1600, 1200, CV_8UC1, bayer->data.data()), MosaicRGGB(reference)), 40.0);

  const AravisStreamStats stats = AravisCameraStreamStats(*p.camera);
  EXPECT_EQ(stats.completed, 1u);  // of the last stream
  EXPECT_EQ(stats.failures, 0u);
}

TEST(AravisCamera, FramesComeInTriggerOrderWithTheirTriggerTimes) {
  InProcess p = StartInProcess();
  ASSERT_TRUE(p.camera->Open().ok());
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  ASSERT_TRUE(p.camera->Configure(s).ok());
  ASSERT_TRUE(p.camera->Arm().ok());
  int64_t last_trigger = 0;
  for (uint64_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(p.camera->SoftwareTrigger().ok());
    auto frame = p.camera->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << frame.status().ToString();
    EXPECT_EQ(frame->sequence, i);
    EXPECT_GT(frame->trigger_time_ns, last_trigger);
    EXPECT_GE(frame->received_time_ns, frame->trigger_time_ns);
    last_trigger = frame->trigger_time_ns;
  }
  EXPECT_EQ(p.camera->WaitFrame(milliseconds(100)).status().code(), StatusCode::kTimeout);
  EXPECT_EQ(AravisCameraStreamStats(*p.camera).completed, 3u);
}

TEST(AravisCamera, InLine0ModeOnlyAPulseOnTheWiredLineTakesAFrame) {
  InProcess p = StartInProcess("trig0");
  ASSERT_TRUE(p.camera->Open().ok());
  ASSERT_TRUE(ArmOnLine(*p.camera, "trig0", PixelFormat::kMono8).ok());
  EXPECT_EQ(p.camera->WaitFrame(milliseconds(200)).status().code(), StatusCode::kTimeout);
  WorldTriggers(*p.w.world).Fire("trig1");  // another line
  EXPECT_EQ(p.camera->WaitFrame(milliseconds(200)).status().code(), StatusCode::kTimeout);
  WorldTriggers(*p.w.world).Fire("trig0");
  auto frame = p.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_EQ(p.feed->frames_rendered(), 1);
}

// Pulses the host notes date the frames in order; a pulse while the camera
// is not acquiring takes no frame, so nothing from before an arming is
// paired with a trigger after it.
TEST(AravisCamera, LinePulsesDateTheFramesAndPulsesWhileDisarmedTakeNone) {
  InProcess p = StartInProcess("trig0");
  ASSERT_TRUE(p.camera->Open().ok());
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  s.trigger = TriggerSource::kLine;
  s.trigger_line = "trig0";
  ASSERT_TRUE(p.camera->Configure(s).ok());
  WorldTriggers(*p.w.world).Fire("trig0");  // not armed yet
  ASSERT_TRUE(p.camera->Arm().ok());
  const int64_t first_ns = SteadyNowNs();
  p.camera->LineTriggerSent(first_ns);
  WorldTriggers(*p.w.world).Fire("trig0");
  const int64_t second_ns = SteadyNowNs();
  p.camera->LineTriggerSent(second_ns);
  WorldTriggers(*p.w.world).Fire("trig0");
  auto first = p.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_EQ(first->trigger_time_ns, first_ns);
  auto second = p.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(second.ok()) << second.status().ToString();
  EXPECT_EQ(second->trigger_time_ns, second_ns);
  EXPECT_EQ(p.camera->WaitFrame(milliseconds(300)).status().code(), StatusCode::kTimeout);
  EXPECT_EQ(p.feed->frames_rendered(), 2);
}

TEST(AravisCamera, AnotherSerialIsRefusedNamingBoth) {
  InProcess p = StartInProcess("", "SIM-CAM-UPPER", kSerial);
  const Status s = p.camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("SIM-CAM-UPPER"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(kSerial), std::string::npos) << s.message();
  EXPECT_EQ(p.camera->state(), DeviceState::kFaulted);
}

TEST(AravisCamera, SettingsOutsideTheCameraAreRefused) {
  InProcess p = StartInProcess();
  ASSERT_TRUE(p.camera->Open().ok());
  CaptureSettings s;
  s.exposure_s = 1e6;
  EXPECT_EQ(p.camera->Configure(s).code(), StatusCode::kOutOfRange);
  s.exposure_s = 0.02;
  s.format = PixelFormat::kEncoded;
  EXPECT_EQ(p.camera->Configure(s).code(), StatusCode::kOutOfRange);

  AravisCameraOptions o = BaseOptions();
  o.nominal.width_px = 100000;
  InProcess big = StartInProcess();
  const SimAravisOptions feed_options{kSerial, kSceneCamera, ""};
  SimAravisFeed* feed = big.feed.get();
  o.connect = [feed, feed_options]() { return OpenSimAravisCamera(*feed, feed_options); };
  auto camera = MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", kSerial, "test"}, o);
  const Status open = camera->Open();
  EXPECT_EQ(open.code(), StatusCode::kOutOfRange) << open.ToString();
  EXPECT_NE(open.message().find("exceeds the sensor"), std::string::npos) << open.message();
}

TEST(AravisCamera, ASerialNoInterfaceHasIsUnavailable) {
  auto camera = MakeAravisCamera({DeviceKind::kCamera, "x", "aravis", "NO-SUCH-CAMERA", "test"},
                                 BaseOptions());
  const Status s = camera->Open();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
  EXPECT_NE(s.message().find("not found on any Aravis interface"), std::string::npos)
      << s.message();
}

TEST(AravisCamera, ConfigErrorsNameTheField) {
  auto root =
      ConfigNode::LoadString("{name: c, backend: aravis, serial: X, buffers: 1}", "rig.yaml");
  auto parsed = ParseAravisCameraOptions(*root);
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.status().message().find("buffers"), std::string::npos)
      << parsed.status().message();
}

// Over GigE Vision on loopback: real UDP streaming through Aravis' GigE fake.
// The small test scene (300 x 400): the fake renders in its own network
// thread, and a slow render (a sanitizer build) would starve its heartbeat;
// frames per second at full size are measured by bench/aravis_bench.
TEST(AravisGigE, StreamsRenderedFramesOverLoopbackWithoutLoss) {
  const World w{hairrig_test::MakeSimWorld({}, /*lights_on=*/true, "tests/data/small_scene.yaml")};
  auto gige = SimGigECamera::Start(w.world, {kSerial, kSceneCamera, ""});
  ASSERT_TRUE(gige.ok()) << gige.status().ToString();
  AravisCameraOptions o = BaseOptions();
  o.nominal.width_px = 300;
  o.nominal.height_px = 400;
  o.address = (*gige)->address();
  auto camera = MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", kSerial, "test"}, o);
  ASSERT_TRUE(camera->Open().ok());
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  s.exposure_s = 0.02;
  ASSERT_TRUE(camera->Configure(s).ok());
  ASSERT_TRUE(camera->Arm().ok());
  cv::Mat grey;
  cv::cvtColor(Reference(w), grey, cv::COLOR_BGR2GRAY);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(camera->SoftwareTrigger().ok());
    auto frame = camera->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << frame.status().ToString();
    EXPECT_GT(Psnr(cv::Mat(400, 300, CV_8UC1, frame->data.data()), grey), 40.0);
  }
  const AravisStreamStats stats = AravisCameraStreamStats(*camera);
  EXPECT_EQ(stats.completed, 4u);
  EXPECT_EQ(stats.failures, 0u);
  EXPECT_EQ(stats.missing_packets, 0u);
  ASSERT_TRUE(camera->Disarm().ok());
  EXPECT_EQ((*gige)->frames_rendered(), 4);
  ASSERT_TRUE(camera->Close().ok());
  // Without an address the camera is found by its serial on Aravis' interfaces.
  o.address.clear();
  auto by_serial = MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", kSerial, "test"}, o);
  const Status found = by_serial->Open();
  EXPECT_TRUE(found.ok()) << found.ToString();
}

// One control packet with an address outside Aravis' fake camera's memory
// (a READMEM at 0xFFFFFFF0) crashed the process it ran in; the guard drops
// such packets in the kernel, and the fake keeps serving. Its discovery
// socket (255.255.255.255:3956) is confined to the loopback interface.
TEST(AravisGigE, HostileControlPacketsDoNotCrashTheFake) {
  const World w{hairrig_test::MakeSimWorld({}, /*lights_on=*/true, "tests/data/small_scene.yaml")};
  auto gige = SimGigECamera::Start(w.world, {kSerial, kSceneCamera, ""});
  ASSERT_TRUE(gige.ok()) << gige.status().ToString();
  const std::string host = (*gige)->address();
  const auto read_test_register =
      hairrig_test::GvcpCommand(hairrig_test::kGvcpReadRegister, {hairrig_test::kFakeTestRegister});
  ASSERT_EQ(hairrig_test::AskGvcp(host, read_test_register), 12);
  for (const auto& packet : hairrig_test::HostileGvcpPackets()) {
    EXPECT_EQ(hairrig_test::AskGvcp(host, packet, 100), -1) << "a hostile packet was answered";
  }
  EXPECT_EQ(hairrig_test::AskGvcp(host, read_test_register), 12);
  int broadcast_sockets = 0;
  for (int fd : OpenDescriptors()) {
    sockaddr_in bound{};
    socklen_t size = sizeof bound;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &size) != 0 ||
        bound.sin_family != AF_INET || ntohs(bound.sin_port) != kGvcpPort ||
        bound.sin_addr.s_addr != htonl(INADDR_BROADCAST)) {
      continue;
    }
    ++broadcast_sockets;
    char device[32] = {};
    socklen_t device_size = sizeof device;
    ASSERT_EQ(getsockopt(fd, SOL_SOCKET, SO_BINDTODEVICE, device, &device_size), 0);
    EXPECT_STREQ(device, "lo");
  }
  EXPECT_LE(broadcast_sockets, 1);
}

}  // namespace
}  // namespace hairrig
