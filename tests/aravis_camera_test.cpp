// The `aravis` camera backend against Aravis' own fake camera fed with the
// rendered world: in-process (ArvFakeDevice) and as a GigE Vision camera on
// 127.0.0.1, over real GVCP/GVSP packets.
#include "drivers/aravis_camera.h"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

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
using hairrig_test::WaitUntil;

using std::chrono::milliseconds;
constexpr char kSerial[] = "SIM-CAM-LOWER";
constexpr int kSceneCamera = 1;

struct World {
  std::shared_ptr<SimWorld> world;  // with its panels on, so that the views are lit
};

World MakeWorld() { return {hairrig_test::MakeSimWorld({}, /*lights_on=*/true)}; }
// The small test scene (300 x 400 views).
World MakeSmallWorld() {
  return {hairrig_test::MakeSimWorld({}, /*lights_on=*/true, "tests/data/small_scene.yaml")};
}

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

// The backend with options `o` on Aravis' in-process fake with serial
// `fake_serial` in world `w`, configured for `device_serial`.
InProcess StartInProcess(const std::string& trigger_line = "",
                         const std::string& fake_serial = kSerial,
                         const std::string& device_serial = kSerial,
                         AravisCameraOptions o = BaseOptions(), World w = MakeWorld()) {
  InProcess p;
  p.w = std::move(w);
  const SimAravisOptions feed_options{fake_serial, kSceneCamera, trigger_line};
  p.feed = std::make_unique<SimAravisFeed>(p.w.world, feed_options);
  SimAravisFeed* feed = p.feed.get();
  o.connect = [feed, feed_options]() { return OpenSimAravisCamera(*feed, feed_options); };
  p.camera = MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", device_serial, "test"}, o);
  return p;
}

cv::Mat Reference(const World& w) {
  return RenderWorldExposure(*w.world, kSceneCamera, ExposeWorldNow(*w.world), 0.02, 0, 0).value();
}
cv::Mat GreyReference(const World& w) {
  cv::Mat grey;
  cv::cvtColor(Reference(w), grey, cv::COLOR_BGR2GRAY);
  return grey;
}

// Configure for Mono8 at 20 ms, software-triggered, then Arm.
Status ArmMono8(Camera& camera) {
  CaptureSettings s;
  s.format = PixelFormat::kMono8;
  s.exposure_s = 0.02;
  HR_RETURN_IF_ERROR(camera.Configure(s));
  return camera.Arm();
}

// A Mono8 frame's PSNR against `grey`, the view it should show.
double MonoPsnr(const Frame& frame, const cv::Mat& grey) {
  return Psnr(
      cv::Mat(frame.height_px, frame.width_px, CV_8UC1, const_cast<uint8_t*>(frame.data.data())),
      grey);
}

// The panel the tests set to a level outside 0..1, which the renderer
// refuses: the simulated camera then has no view for its frame.
constexpr char kPanel[] = "top";

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

// A trigger that finds every buffer of the pool holding a frame not yet
// taken waits for one: the frames come in order, each its trigger's view,
// and none is reported lost (the stream counts underruns meanwhile).
TEST(AravisCamera, ATriggerBeyondTheFreeBuffersWaitsForOneAndNoFrameIsLost) {
  AravisCameraOptions o = BaseOptions();
  o.buffers = 2;
  InProcess p = StartInProcess("", kSerial, kSerial, o);
  ASSERT_TRUE(p.camera->Open().ok());
  const cv::Mat grey = GreyReference(p.w);
  ASSERT_TRUE(ArmMono8(*p.camera).ok());
  for (int i = 1; i <= 2; ++i) {
    ASSERT_TRUE(p.camera->SoftwareTrigger().ok());
    ASSERT_TRUE(WaitUntil([&] { return p.feed->frames_rendered() == i; })) << "frame " << i;
  }
  ASSERT_TRUE(WaitUntil([&] { return AravisCameraStreamStats(*p.camera).underruns > 0; }))
      << "both buffers hold a frame, so the stream finds none free";
  ASSERT_TRUE(p.camera->SoftwareTrigger().ok());
  for (uint64_t i = 0; i < 3; ++i) {
    auto frame = p.camera->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << "frame " << i << ": " << frame.status().ToString();
    EXPECT_EQ(frame->sequence, i);
    EXPECT_GT(MonoPsnr(*frame, grey), 40.0) << "frame " << i;
  }
  EXPECT_EQ(p.feed->frames_rendered(), 3);
}

// Aravis' fake numbers its frames from 65401 (to find wrap-around bugs): the
// numbers wrap from 65535 to 1 within a stream, and no frame is lost there.
TEST(AravisCamera, FrameIdsWrapAroundWithoutAFalseLoss) {
  AravisCameraOptions o = BaseOptions();
  o.nominal.width_px = 300;
  o.nominal.height_px = 400;
  InProcess p = StartInProcess("", kSerial, kSerial, o, MakeSmallWorld());
  ASSERT_TRUE(p.camera->Open().ok());
  const cv::Mat grey = GreyReference(p.w);
  ASSERT_TRUE(ArmMono8(*p.camera).ok());
  for (uint64_t i = 0; i < 140; ++i) {
    ASSERT_TRUE(p.camera->SoftwareTrigger().ok());
    auto frame = p.camera->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << "frame " << i << ": " << frame.status().ToString();
    ASSERT_EQ(frame->sequence, i);
    ASSERT_GT(MonoPsnr(*frame, grey), 40.0) << "frame " << i;
  }
}

// A frame the simulated camera has no view for (here: the renderer refuses a
// panel level) is a fault of that frame, never an image; the next is fine.
TEST(AravisCamera, AFrameWithoutTheViewIsAFaultNotAnImage) {
  InProcess p = StartInProcess();
  ASSERT_TRUE(p.camera->Open().ok());
  const cv::Mat grey = GreyReference(p.w);
  ASSERT_TRUE(SetWorldLightLevel(*p.w.world, kPanel, 1.5).ok());
  auto broken = ShootOnce(*p.camera, PixelFormat::kMono8);
  ASSERT_FALSE(broken.ok()) << "a frame without the view came as an image";
  EXPECT_EQ(broken.status().code(), StatusCode::kCorruptData) << broken.status().ToString();
  EXPECT_NE(broken.status().message().find("sent no image"), std::string::npos)
      << broken.status().message();
  EXPECT_EQ(p.feed->frames_rendered(), 1);
  ASSERT_TRUE(SetWorldLightLevel(*p.w.world, kPanel, 1.0).ok());
  auto frame = ShootOnce(*p.camera, PixelFormat::kMono8);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_GT(MonoPsnr(*frame, grey), 40.0);
}

// An incomplete buffer counts by its id (the backend reports it itself), so a
// frame dropped right after it is seen as a gap; a buffer without an id (0)
// counts as the frame after the last one.
TEST(AravisFrameIds, AFrameDroppedAfterAnIncompleteOneIsAGap) {
  AravisFrameIds ids(/*skips_zero=*/true, /*counts_frames=*/true);
  ASSERT_TRUE(ids.Next(7, "camera").ok());
  ASSERT_TRUE(ids.Next(8, "camera").ok());    // arrived incomplete
  const Status gap = ids.Next(10, "camera");  // 9 dropped
  EXPECT_EQ(gap.code(), StatusCode::kCorruptData) << gap.ToString();
  EXPECT_NE(gap.message().find("frame id 10 after 8 means 1 frame(s) lost"), std::string::npos)
      << gap.message();

  AravisFrameIds unnumbered(true, true);
  ASSERT_TRUE(unnumbered.Next(65534, "camera").ok());
  ASSERT_TRUE(unnumbered.Next(0, "camera").ok());  // no image, no id: frame 65535
  EXPECT_TRUE(unnumbered.Next(1, "camera").ok()) << "the ids wrap from 65535 to 1";
  ASSERT_TRUE(unnumbered.Next(0, "camera").ok());  // frame 2
  const Status lost = unnumbered.Next(4, "camera");
  EXPECT_EQ(lost.code(), StatusCode::kCorruptData) << lost.ToString();
  EXPECT_NE(lost.message().find("1 frame(s) lost"), std::string::npos) << lost.message();
}

// After a gap no frame can be paired with its trigger: every later one gets
// the same report until the camera is armed again (Reset).
TEST(AravisFrameIds, AfterAGapEveryFrameIsRefusedUntilReset) {
  AravisFrameIds ids(/*skips_zero=*/true, /*counts_frames=*/true);
  ASSERT_TRUE(ids.Next(1, "camera").ok());
  const Status gap = ids.Next(3, "camera", "; a note");
  ASSERT_EQ(gap.code(), StatusCode::kCorruptData) << gap.ToString();
  EXPECT_NE(gap.message().find("a note"), std::string::npos) << gap.message();
  EXPECT_NE(gap.message().find("re-arm the camera"), std::string::npos) << gap.message();
  const Status next = ids.Next(4, "camera");
  EXPECT_EQ(next.code(), StatusCode::kCorruptData);
  EXPECT_EQ(next.message(), gap.message());
  EXPECT_EQ(ids.gap().message(), gap.message());
  ids.Reset();
  EXPECT_TRUE(ids.gap().ok());
  EXPECT_TRUE(ids.Next(9, "camera").ok());
  EXPECT_TRUE(ids.Next(10, "camera").ok());
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
  InProcess big = StartInProcess("", kSerial, kSerial, o);
  const Status open = big.camera->Open();
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
struct GigE {
  World w = MakeSmallWorld();
  std::unique_ptr<SimGigECamera> fake;
  AravisCameraOptions options;
  std::unique_ptr<Camera> camera;
  cv::Mat grey;  // the view in Mono8, rendered first: the fake's renders then only expose it
};

// The GigE fake of the small scene, and the backend on it with `buffers`,
// opened and armed for Mono8.
void StartGigE(GigE* g, int buffers = 8) {
  auto fake = SimGigECamera::Start(g->w.world, {kSerial, kSceneCamera, ""});
  ASSERT_TRUE(fake.ok()) << fake.status().ToString();
  g->fake = std::move(fake).value();
  g->options = BaseOptions();
  g->options.nominal.width_px = 300;
  g->options.nominal.height_px = 400;
  g->options.buffers = buffers;
  g->options.address = g->fake->address();
  g->camera =
      MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", kSerial, "test"}, g->options);
  g->grey = GreyReference(g->w);
  ASSERT_TRUE(g->camera->Open().ok());
  ASSERT_TRUE(ArmMono8(*g->camera).ok());
}

TEST(AravisGigE, StreamsRenderedFramesOverLoopbackWithoutLoss) {
  GigE g;
  ASSERT_NO_FATAL_FAILURE(StartGigE(&g));
  Camera* camera = g.camera.get();
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(camera->SoftwareTrigger().ok());
    auto frame = camera->WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << frame.status().ToString();
    EXPECT_GT(MonoPsnr(*frame, g.grey), 40.0);
  }
  const AravisStreamStats stats = AravisCameraStreamStats(*camera);
  EXPECT_EQ(stats.completed, 4u);
  EXPECT_EQ(stats.failures, 0u);
  EXPECT_EQ(stats.missing_packets, 0u);
  ASSERT_TRUE(camera->Disarm().ok());
  EXPECT_EQ(g.fake->frames_rendered(), 4);
  ASSERT_TRUE(camera->Close().ok());
  // Without an address the camera is found by its serial on Aravis' interfaces.
  g.options.address.clear();
  auto by_serial =
      MakeAravisCamera({DeviceKind::kCamera, "lower", "aravis", kSerial, "test"}, g.options);
  const Status found = by_serial->Open();
  EXPECT_TRUE(found.ok()) << found.ToString();
}

// One good frame, then a trigger whose frame the feed cannot render (a panel
// asked for 150 %). The good frame gives the stream its frame id: a frame
// lost before any arrived leaves no gap to see (the timeout uses up its trigger).
void TriggerAFrameWithoutTheViewAfterAGoodOne(GigE& g) {
  Camera& camera = *g.camera;
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  ASSERT_TRUE(camera.WaitFrame(kFrameWait).ok());
  ASSERT_TRUE(SetWorldLightLevel(*g.w.world, kPanel, 1.5).ok());
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  ASSERT_TRUE(WaitUntil([&] { return g.fake->frames_rendered() == 2; }));
}

// A frame the fake has no view for is never sent: the wait for it times
// out, and the next frame's id shows it lost. The frames after that one
// cannot be paired with their triggers either: each gets the same report
// until the camera is armed again.
TEST(AravisGigE, AFrameWithoutTheViewIsNeverSent) {
  GigE g;
  ASSERT_NO_FATAL_FAILURE(StartGigE(&g));
  Camera& camera = *g.camera;
  ASSERT_NO_FATAL_FAILURE(TriggerAFrameWithoutTheViewAfterAGoodOne(g));
  const auto none = camera.WaitFrame(milliseconds(500));
  EXPECT_EQ(none.status().code(), StatusCode::kTimeout)
      << (none.ok() ? "a frame without the view came as an image" : none.status().ToString());
  ASSERT_TRUE(SetWorldLightLevel(*g.w.world, kPanel, 1.0).ok());
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  const auto after = camera.WaitFrame(kFrameWait);
  ASSERT_FALSE(after.ok()) << "the frame after a lost one was paired with the lost one's trigger";
  EXPECT_EQ(after.status().code(), StatusCode::kCorruptData) << after.status().ToString();
  EXPECT_NE(after.status().message().find("1 frame(s) lost"), std::string::npos)
      << after.status().message();
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  ASSERT_TRUE(WaitUntil([&] { return AravisCameraStreamStats(camera).completed == 3; }))
      << "the frame after the gap arrives";
  const auto later = camera.WaitFrame(kFrameWait);
  ASSERT_FALSE(later.ok()) << "a frame after the gap was paired with the trigger before its own";
  EXPECT_EQ(later.status().code(), StatusCode::kCorruptData) << later.status().ToString();
  EXPECT_EQ(later.status().message(), after.status().message());
  EXPECT_NE(after.status().message().find("re-arm the camera"), std::string::npos)
      << after.status().message();
  // Armed again, it delivers the view.
  ASSERT_TRUE(camera.Disarm().ok());
  ASSERT_TRUE(camera.Arm().ok());
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  const auto frame = camera.WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_GT(MonoPsnr(*frame, g.grey), 40.0);
}

// A frame that arrives while both buffers hold frames not yet taken is
// dropped by the stream: the frames before it come as they were, and the
// dropped one never comes as an image.
TEST(AravisGigE, AFrameDroppedForWantOfABufferIsAFaultNotAMispairedFrame) {
  GigE g;
  ASSERT_NO_FATAL_FAILURE(StartGigE(&g, /*buffers=*/2));
  Camera& camera = *g.camera;
  for (int i = 1; i <= 3; ++i) {  // the fake takes one pending trigger at a time
    ASSERT_TRUE(camera.SoftwareTrigger().ok());
    ASSERT_TRUE(WaitUntil([&] { return g.fake->frames_rendered() == i; })) << "frame " << i;
  }
  ASSERT_TRUE(WaitUntil([&] { return AravisCameraStreamStats(camera).underruns > 0; }))
      << "the third frame found no free buffer";
  for (uint64_t i = 0; i < 2; ++i) {
    auto frame = camera.WaitFrame(kFrameWait);
    ASSERT_TRUE(frame.ok()) << "frame " << i << ": " << frame.status().ToString();
    EXPECT_EQ(frame->sequence, i);
    EXPECT_GT(MonoPsnr(*frame, g.grey), 40.0);
  }
  // Either the dropped frame's wait times out and the next frame shows the
  // gap, or the packets that came after a buffer was free arrive as an
  // incomplete frame.
  auto third = camera.WaitFrame(milliseconds(2000));
  ASSERT_FALSE(third.ok()) << "the dropped frame came as an image";
  if (third.status().code() == StatusCode::kTimeout) {
    EXPECT_NE(third.status().message().find("no free buffer"), std::string::npos)
        << third.status().message();
    ASSERT_TRUE(camera.SoftwareTrigger().ok());
    third = camera.WaitFrame(kFrameWait);
    ASSERT_FALSE(third.ok()) << "the frame after the dropped one was paired with its trigger";
  }
  EXPECT_EQ(third.status().code(), StatusCode::kCorruptData) << third.status().ToString();
}

// A frame without the view leaves the GigE fake dropping every packet until
// the feed fills the next frame; a feed attached again without rendering
// (Aravis' own pattern, which the feed does not fill) must not keep that.
TEST(AravisGigE, TheFeedAttachedAgainAfterAWithheldFrameStreams) {
  GigE g;
  ASSERT_NO_FATAL_FAILURE(StartGigE(&g));
  Camera& camera = *g.camera;
  ASSERT_NO_FATAL_FAILURE(TriggerAFrameWithoutTheViewAfterAGoodOne(g));
  EXPECT_EQ(camera.WaitFrame(milliseconds(500)).status().code(), StatusCode::kTimeout);
  g.fake->SetRender(false);  // detaches the feed and attaches it again
  ASSERT_TRUE(camera.Disarm().ok());
  ASSERT_TRUE(camera.Arm().ok());
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  const auto pattern = camera.WaitFrame(kFrameWait);
  ASSERT_TRUE(pattern.ok()) << "the fake drops every frame: " << pattern.status().ToString();
  EXPECT_LT(MonoPsnr(*pattern, g.grey), 30.0) << "Aravis' own pattern, not the view";
  g.fake->SetRender(true);
  ASSERT_TRUE(SetWorldLightLevel(*g.w.world, kPanel, 1.0).ok());
  ASSERT_TRUE(camera.SoftwareTrigger().ok());
  const auto view = camera.WaitFrame(kFrameWait);
  ASSERT_TRUE(view.ok()) << view.status().ToString();
  EXPECT_GT(MonoPsnr(*view, g.grey), 40.0);
}

// Aravis lets a second GigE fake bind 127.0.0.1:3956; the client would then
// get the first one's answers and images. The second is refused, and the
// first serves on.
TEST(AravisGigE, ASecondFakeOnThePortIsRefused) {
  GigE g;
  ASSERT_NO_FATAL_FAILURE(StartGigE(&g));
  auto second = SimGigECamera::Start(g.w.world, {"SIM-CAM-OTHER", kSceneCamera, ""});
  ASSERT_FALSE(second.ok()) << "a second GigE fake started on the port";
  EXPECT_EQ(second.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(second.status().message().find("127.0.0.1:3956 is already served"), std::string::npos)
      << second.status().message();
  ASSERT_TRUE(g.camera->SoftwareTrigger().ok());
  const auto frame = g.camera->WaitFrame(kFrameWait);
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_GT(MonoPsnr(*frame, g.grey), 40.0);
}

// A socket is the fake's when it was opened since the fake started, even at
// a descriptor number that was open before (closed meanwhile, and reused):
// it is guarded, and taken for no other server on the port.
TEST(AravisGigE, ASocketAtADescriptorReusedSinceTheStartIsTheFakes) {
  struct Socket {
    int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    ~Socket() {
      if (fd >= 0) close(fd);
    }
  };
  const Socket reused;
  ASSERT_GE(reused.fd, 0);
  const std::set<uint64_t> before = OpenSocketInodes();
  {
    const Socket opened;
    ASSERT_GE(opened.fd, 0);
    ASSERT_EQ(dup2(opened.fd, reused.fd), reused.fd);  // closes the socket that was there
  }
  sockaddr_in gvcp{};
  gvcp.sin_family = AF_INET;
  gvcp.sin_port = htons(kGvcpPort);
  gvcp.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(reused.fd, reinterpret_cast<const sockaddr*>(&gvcp), sizeof gvcp), 0)
      << "127.0.0.1:" << kGvcpPort << ": " << std::strerror(errno);
  const auto guarded = GuardGvFakeSockets(before, "127.0.0.1", {64, 64});
  ASSERT_TRUE(guarded.ok()) << guarded.status().ToString();
  EXPECT_EQ(guarded->filtered, 1);
  const Status sole = RequireSoleGvcpServer(before, "127.0.0.1");
  EXPECT_TRUE(sole.ok()) << sole.ToString();
}

// One control packet with an address outside Aravis' fake camera's memory
// (a READMEM at 0xFFFFFFF0) crashed the process it ran in; the guard drops
// such packets in the kernel, and the fake keeps serving. Its discovery
// socket (255.255.255.255:3956) is confined to the loopback interface.
TEST(AravisGigE, HostileControlPacketsDoNotCrashTheFake) {
  const World w = MakeSmallWorld();
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
